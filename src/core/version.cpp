#include "qdmr/core/version.hpp"

namespace qdmr {

const char* version() { return QDMR_VERSION; }

}  // namespace qdmr
