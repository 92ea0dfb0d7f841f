#pragma once
// QDMR_TEST_ASAN is defined in builds with AddressSanitizer, by GCC (__SANITIZE_ADDRESS__) or clang (which defines
// no such macro, only __has_feature(address_sanitizer)): tests that bound time or resident memory relax or skip
// their bounds there.
#if defined(__SANITIZE_ADDRESS__)
#define QDMR_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define QDMR_TEST_ASAN 1
#endif
#endif
