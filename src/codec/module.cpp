// libqdmr_imageio.so: the OpenImageIO backend as a module the `qdmr` command loads on first use (lazy.cpp).
#include "codec/backend.hpp"

extern "C" [[gnu::visibility("default")]] const qdmr::imageio::Backend* qdmr_imageio_backend_v1() {
  return &qdmr::imageio::oiio_backend();
}
