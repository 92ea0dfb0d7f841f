#include "qdmr/texture/format.hpp"

#include <array>
#include <utility>

namespace qdmr {
namespace {

constexpr std::array<std::pair<TexelFormat, const char*>, 5> kNames = {{
    {TexelFormat::R8, "r8"},
    {TexelFormat::RG8, "rg8"},
    {TexelFormat::RGBA8, "rgba8"},
    {TexelFormat::R16, "r16"},
    {TexelFormat::R32F, "r32f"},
}};

}  // namespace

std::string format_name(TexelFormat f) {
  for (const auto& [format, name] : kNames)
    if (format == f) return name;
  return "unknown";
}

std::optional<TexelFormat> parse_format(const std::string& name) {
  for (const auto& [format, known] : kNames)
    if (name == known) return format;
  return std::nullopt;
}

}  // namespace qdmr
