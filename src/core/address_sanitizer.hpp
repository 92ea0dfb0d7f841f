#pragma once
// QDMR_ADDRESS_SANITIZER is defined in builds with AddressSanitizer, by GCC (__SANITIZE_ADDRESS__) or clang (which
// defines no such macro, only __has_feature(address_sanitizer)). Code that maps memory itself, and tests that bound
// time or resident memory, behave differently there.
#if defined(__SANITIZE_ADDRESS__)
#define QDMR_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define QDMR_ADDRESS_SANITIZER 1
#endif
#endif
