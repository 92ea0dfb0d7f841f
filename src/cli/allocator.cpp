// The qdmr command's allocator settings. jemalloc (linked into the command only, see cmake/Dependencies.cmake)
// reads them at its first allocation:
//   thp:always            its memory on transparent huge pages (the kernel's `madvise` mode needs the advice);
//                         on virtual machines a fresh 4 KiB page costs a fault exit, a fresh 2 MiB page one per
//                         2 MiB;
//   metadata_thp:auto     its own metadata too, once it grows;
//   dirty/muzzy decay -1  freed pages are kept and reused, never handed back: the frame's buffers take the pages
//                         the preparation's temporaries freed, without a new first touch. Resident memory stays at
//                         the process's peak, which the plan's memory estimate already bounds.
// The allocator never changes a result: no computation reads memory it did not write.
#if defined(QDMR_JEMALLOC)
// jemalloc's documented configuration symbol, declared as its header declares it.
extern "C" const char* malloc_conf;
const char* malloc_conf = "thp:always,metadata_thp:auto,dirty_decay_ms:-1,muzzy_decay_ms:-1";
#endif
