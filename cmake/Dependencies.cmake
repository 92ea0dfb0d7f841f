# Every dependency comes from Debian's packages, found in CONFIG mode (see ../shared/DEPENDENCIES.md).
find_package(glm CONFIG REQUIRED)
find_package(OpenImageIO CONFIG REQUIRED)
find_package(TBB CONFIG REQUIRED)
find_package(xtl CONFIG REQUIRED)      # xsimd's target links a bare xtl
find_package(xsimd CONFIG REQUIRED)
find_package(CLI11 CONFIG REQUIRED)
find_package(nlohmann_json CONFIG REQUIRED)
find_package(tinyobjloader CONFIG REQUIRED)  # reports "2rc10": no version argument
find_package(TinyGLTF 2.7 CONFIG REQUIRED)  # glTF 2.0 (mesh/gltf.cpp); its images go through qdmr's readers
find_package(OpenSSL REQUIRED COMPONENTS Crypto)  # SHA-1 (core/sha1.hpp); FindOpenSSL, Debian ships no config
find_package(PNG REQUIRED)  # codec/png_writer.hpp: PNG output without the image module; FindPNG
find_package(JPEG REQUIRED)  # codec/native_reader.hpp: JPEG textures without the image module; FindJPEG
find_package(TIFF REQUIRED)  # ... and most TIFF textures; FindTIFF
find_package(OpenEXR CONFIG REQUIRED)  # ... and OpenEXR textures
# codec/png_writer.hpp: the PNG's pixel data compressed by ISA-L's igzip by default (about 2.5 times libdeflate's
# fastest level) or by libdeflate for the smallest file; Debian's libisal-dev and libdeflate-dev ship pkg-config
# files only.
find_package(PkgConfig REQUIRED)
pkg_check_modules(LIBISAL REQUIRED IMPORTED_TARGET libisal)
pkg_check_modules(LIBDEFLATE REQUIRED IMPORTED_TARGET libdeflate)

# The qdmr command's allocator (src/cli/allocator.cpp): jemalloc, which keeps freed memory for reuse and backs it
# with transparent huge pages, so a one-shot render does not pay the first touch of every buffer it allocates
# (docs/performance.md, "Cold frames"). Not in sanitizer builds, whose runtime replaces the allocator.
if(NOT QDMR_SANITIZE AND NOT QDMR_FUZZ)
  pkg_check_modules(JEMALLOC REQUIRED IMPORTED_TARGET jemalloc)
endif()

# OpenImageIO's target names /usr/include/opencv4, which exists only with libopencv-dev.
foreach(prop INTERFACE_INCLUDE_DIRECTORIES INTERFACE_SYSTEM_INCLUDE_DIRECTORIES)
  get_target_property(_dirs OpenImageIO::OpenImageIO ${prop})
  if(_dirs)
    list(FILTER _dirs EXCLUDE REGEX "opencv4")
    set_target_properties(OpenImageIO::OpenImageIO PROPERTIES ${prop} "${_dirs}")
  endif()
endforeach()

if(QDMR_BUILD_TESTS)
  find_package(GTest CONFIG REQUIRED)
endif()
if(QDMR_BUILD_BENCH)
  find_package(benchmark CONFIG REQUIRED)
endif()
