# Run after each build of a GoogleTest binary (qdmr_add_gtest_suites in tests/CMakeLists.txt): lists the binary's
# test suites and writes CTEST_FILE, which gives CTest one test per suite, named after it and running
# `<binary> --gtest_filter=<suite>.*`.
#
# Why suites and not test cases: each test binary links OpenImageIO, and each process start resolves its ~260 shared
# libraries (~0.4 s of CPU in a release build, ~0.85 s under ASan), more than most tests take. One process per suite
# (63 + 15 of them) instead of one per test case (290 + 113) saves CI several minutes of CPU.
#
# Input: TEST_EXECUTABLE, CTEST_FILE, TIMEOUT, LABELS (optional).
execute_process(COMMAND "${TEST_EXECUTABLE}" --gtest_list_tests
  OUTPUT_VARIABLE listing ERROR_VARIABLE errors RESULT_VARIABLE status TIMEOUT 60)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${TEST_EXECUTABLE} --gtest_list_tests failed (${status}):\n${listing}${errors}")
endif()
string(REPLACE "\n" ";" lines "${listing}")
set(content "# Written by tests/gtest_suites.cmake from `${TEST_EXECUTABLE} --gtest_list_tests`.\n")
set(count 0)
foreach(line IN LISTS lines)
  # A suite's line: its name and a dot, maybe followed by "  # TypeParam = ..."; its tests' lines are indented.
  if(line MATCHES "^([A-Za-z0-9_/]+)\\.(  #.*)?$")
    set(suite "${CMAKE_MATCH_1}")
    string(APPEND content "add_test([==[${suite}]==] [==[${TEST_EXECUTABLE}]==] [==[--gtest_filter=${suite}.*]==])\n"
      "set_tests_properties([==[${suite}]==] PROPERTIES TIMEOUT ${TIMEOUT}")
    if(LABELS)
      string(APPEND content " LABELS [==[${LABELS}]==]")
    endif()
    string(APPEND content ")\n")
    math(EXPR count "${count} + 1")
  endif()
endforeach()
if(count EQUAL 0)
  message(FATAL_ERROR "${TEST_EXECUTABLE} lists no test suite:\n${listing}")
endif()
file(WRITE "${CTEST_FILE}" "${content}")
