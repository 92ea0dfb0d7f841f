// The library's and the tests' image backend: OpenImageIO linked in (see backend.hpp).
#include "codec/backend.hpp"

namespace qdmr::imageio {

const Backend& backend() { return oiio_backend(); }

}  // namespace qdmr::imageio
