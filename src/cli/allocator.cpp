// The qdmr command's allocator settings. jemalloc (linked into the command only, see cmake/Dependencies.cmake)
// reads them at its first allocation:
//   dirty/muzzy decay -1  freed pages are kept and reused, never handed back: the frame's buffers take the pages
//                         the preparation's temporaries freed, without a new first touch. Resident memory stays at
//                         the process's peak, which the plan's memory estimate already bounds.
// Its memory is not asked onto transparent huge pages (jemalloc's thp:default; the framebuffer and the zeroed
// buffers advise their own): on the AVX2 and AVX-512 VMs measured, a fresh 2 MiB page cost more per MB than 4 KiB
// ones: the cold terrain prepared in 380-462 ms against 493-653 with thp:always on Zen 3, warm frames alike
// (docs/performance-history.md). MALLOC_CONF=thp:always turns it back on.
// The allocator never changes a result: no computation reads memory it did not write.
#if defined(QDMR_JEMALLOC)
// jemalloc's documented configuration symbol, declared as its header declares it.
extern "C" const char* malloc_conf;
const char* malloc_conf = "dirty_decay_ms:-1,muzzy_decay_ms:-1";
#endif
