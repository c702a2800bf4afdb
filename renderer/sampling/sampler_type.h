#pragma once
// Which sample generator a render uses (scene key `sampler: {type: ...}`, `--sampler`). A tiny
// header of its own so the scene description need not pull in the generators.
#include <optional>
#include <string_view>

namespace omega {

enum class SamplerType { Sobol, Independent };

inline const char* sampler_name(SamplerType t) { return t == SamplerType::Sobol ? "sobol" : "independent"; }

inline std::optional<SamplerType> sampler_from_name(std::string_view s) {
    if (s == "sobol") return SamplerType::Sobol;
    if (s == "independent") return SamplerType::Independent;
    return std::nullopt;
}

}  // namespace omega
