#pragma once
// The instruction sets qdmr's draw kernels are compiled for, in one binary; one is chosen per process (or per
// Renderer) from what the CPU has, or forced (`--isa`, or the QDMR_ISA environment variable for library users).
// Every ISA draws the same bits.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace qdmr {

enum class Isa { Auto, Sse42, Avx2, Avx512 };

const char* isa_name(Isa isa);                         // "auto", "sse4.2", "avx2", "avx512"
std::optional<Isa> parse_isa(std::string_view name);   // the names above
bool cpu_supports(Isa isa);                            // from CPUID (Auto: true)
std::vector<Isa> built_isas();                         // the kernels in this binary, best first
std::vector<Isa> usable_isas();                        // built and supported by this CPU, best first

// The ISA to draw with: Auto takes $QDMR_ISA when set, else the best usable one. Throws qdmr::Error naming
// `where` when the ISA is unknown, not built into this binary, or not supported by this CPU.
Isa resolve_isa(Isa requested, const std::string& where = "--isa");
Isa resolve_isa(std::string_view requested, const std::string& where = "--isa");

}  // namespace qdmr
