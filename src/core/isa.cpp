#include "qdmr/core/isa.hpp"

#include <cpuid.h>

#include <algorithm>
#include <cstdlib>

#include "qdmr/core/error.hpp"

namespace qdmr {

const char* isa_name(Isa isa) {
  switch (isa) {
    case Isa::Auto: return "auto";
    case Isa::Sse42: return "sse4.2";
    case Isa::Avx2: return "avx2";
    case Isa::Avx512: return "avx512";
  }
  return "?";
}

std::optional<Isa> parse_isa(std::string_view name) {
  for (Isa isa : {Isa::Auto, Isa::Sse42, Isa::Avx2, Isa::Avx512})
    if (name == isa_name(isa)) return isa;
  return std::nullopt;
}

namespace {

// F16C from CPUID leaf 1, ECX bit 29 (clang's __builtin_cpu_supports does not know "f16c").
bool cpu_has_f16c() {
  unsigned a = 0, b = 0, c = 0, d = 0;
  return __get_cpuid(1, &a, &b, &c, &d) && (c & (1u << 29)) != 0;
}

}  // namespace

bool cpu_supports(Isa isa) {
  // GCC's CPUID probe (it also checks that the OS saves the wider registers).
  __builtin_cpu_init();
  switch (isa) {
    case Isa::Auto: return true;
    case Isa::Sse42: return __builtin_cpu_supports("sse4.2") && __builtin_cpu_supports("popcnt");
    case Isa::Avx2: return __builtin_cpu_supports("avx2") && cpu_has_f16c() && __builtin_cpu_supports("popcnt");
    case Isa::Avx512:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
             __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
             __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("popcnt");
  }
  return false;
}

std::vector<Isa> built_isas() {
  std::vector<Isa> isas;
#ifdef QDMR_KERNEL_AVX512
  isas.push_back(Isa::Avx512);
#endif
#ifdef QDMR_KERNEL_AVX2
  isas.push_back(Isa::Avx2);
#endif
#ifdef QDMR_KERNEL_SSE42
  isas.push_back(Isa::Sse42);
#endif
  return isas;
}

std::vector<Isa> usable_isas() {
  std::vector<Isa> isas;
  for (Isa isa : built_isas())
    if (cpu_supports(isa)) isas.push_back(isa);
  return isas;
}

Isa resolve_isa(Isa requested, const std::string& where) {
  if (requested == Isa::Auto) {
    if (const char* env = std::getenv("QDMR_ISA"); env && *env) return resolve_isa(std::string_view(env), "QDMR_ISA");
    const std::vector<Isa> usable = usable_isas();
    if (usable.empty()) throw Error(where, "this CPU has none of the instruction sets qdmr is built for (SSE4.2 at least)");
    return usable.front();
  }
  std::string built;
  for (Isa isa : built_isas()) built += (built.empty() ? "" : ", ") + std::string(isa_name(isa));
  const std::vector<Isa> have = built_isas();
  if (!cpu_supports(requested))
    throw Error(where, std::string("this CPU does not support ") + isa_name(requested));
  if (std::find(have.begin(), have.end(), requested) == have.end())
    throw Error(where, std::string(isa_name(requested)) + " is not built into this binary (built: " + built + ")");
  return requested;
}

Isa resolve_isa(std::string_view requested, const std::string& where) {
  const std::optional<Isa> isa = parse_isa(requested);
  if (!isa) throw Error(where, "unknown ISA '" + std::string(requested) + "' (valid: auto, sse4.2, avx2, avx512)");
  return resolve_isa(*isa, where);
}

}  // namespace qdmr
