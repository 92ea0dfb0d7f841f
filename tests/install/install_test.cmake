# Run by CTest (test "install.find_package", label "slow"; see tests/CMakeLists.txt): installs the build into
# a fresh prefix, then configures, builds and runs docs/example against it with the build's generator and
# compiler, as a user of find_package(qdmr) would. Everything stays in WORK_DIR for inspection.
foreach(var BUILD_DIR SOURCE_DIR WORK_DIR GENERATOR CXX_COMPILER BUILD_TYPE)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "install_test.cmake needs -D${var}=...")
  endif()
endforeach()

function(run)
  string(JOIN " " command ${ARGN})
  message(STATUS "${command}")
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE output ERROR_VARIABLE output)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "failed (${code}): ${command}\n${output}")
  endif()
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")
run("${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}" --config "${BUILD_TYPE}")

# The installed package must stand alone: no path into the source or build tree.
file(GLOB_RECURSE package_files "${prefix}/lib*/cmake/qdmr/*.cmake")
if(NOT package_files)
  message(FATAL_ERROR "no CMake package files installed under ${prefix}")
endif()
foreach(file IN LISTS package_files)
  file(READ "${file}" text)
  foreach(tree "${SOURCE_DIR}" "${BUILD_DIR}")
    string(FIND "${text}" "${tree}" at)
    if(NOT at EQUAL -1)
      message(FATAL_ERROR "${file} refers to ${tree}")
    endif()
  endforeach()
endforeach()

set(example_build "${WORK_DIR}/build")
set(configure "${CMAKE_COMMAND}" -S "${SOURCE_DIR}/docs/example" -B "${example_build}" -G "${GENERATOR}"
    "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}" "-DCMAKE_BUILD_TYPE=${BUILD_TYPE}" "-DCMAKE_PREFIX_PATH=${prefix}"
    -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
if(MAKE_PROGRAM)
  list(APPEND configure "-DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM}")
endif()
run(${configure})
file(STRINGS "${example_build}/CMakeCache.txt" found REGEX "^qdmr_DIR:")
if(NOT found MATCHES "=${prefix}/")
  message(FATAL_ERROR "the example found another qdmr: ${found}")
endif()
run("${CMAKE_COMMAND}" --build "${example_build}" --config "${BUILD_TYPE}")

set(program "${example_build}/render_plane")
if(NOT EXISTS "${program}")
  set(program "${example_build}/${BUILD_TYPE}/render_plane")  # multi-config generators
endif()
set(image "${WORK_DIR}/plane.png")
run("${program}" "${SOURCE_DIR}/scenes/plane.json" "${image}")

# The PNG header holds the size: 160x90 as the example asks.
file(READ "${image}" header OFFSET 16 LIMIT 8 HEX)
if(NOT header STREQUAL "000000a00000005a")
  message(FATAL_ERROR "${image}: expected a 160x90 PNG, header size bytes are ${header}")
endif()
message(STATUS "installed qdmr works: ${image}")

# The installed command loads its image module from lib/qdmr/ relative to itself (src/codec/lazy.cpp): an
# OpenEXR output goes through it (PNG is written, and PNG and JPEG textures are read, without it).
set(command_image "${WORK_DIR}/command.exr")
run("${prefix}/bin/qdmr" render "${SOURCE_DIR}/scenes/plane.json" -o "${command_image}" --width 48 --height 32)
file(READ "${command_image}" magic LIMIT 4 HEX)
if(NOT magic STREQUAL "762f3101")
  message(FATAL_ERROR "${command_image}: expected an OpenEXR file from the installed qdmr, its first bytes are ${magic}")
endif()
message(STATUS "installed qdmr command writes images through its module: ${command_image}")

# The Python package (when the build has it): installed where Debian's python3 imports packages from this prefix
# (PREFIX/lib/python3.X/dist-packages, on sys.path for /usr/local), standing alone: an EXR written through the image
# module it keeps beside itself.
if(DEFINED PYTHON_SITE AND PYTHON)
  set(site "${prefix}/${PYTHON_SITE}")
  if(NOT EXISTS "${site}/qdmr/__init__.py" OR NOT EXISTS "${site}/qdmr/libqdmr_imageio.so")
    message(FATAL_ERROR "the Python package qdmr is not installed in ${site}")
  endif()
  set(python_image "${WORK_DIR}/python.exr")
  run("${CMAKE_COMMAND}" -E env "PYTHONPATH=${site}" "${PYTHON}" -c
    "import numpy, qdmr, sys; assert qdmr.__file__.startswith(sys.argv[1]), qdmr.__file__; qdmr.write_image(numpy.ones((4, 6, 3), numpy.float32), sys.argv[2]); assert qdmr.read_image(sys.argv[2]).shape == (4, 6, 3)"
    "${site}" "${python_image}")
  message(STATUS "installed Python package qdmr works: ${python_image}")
endif()
