#pragma once
// The breakdown's chart (docs/breakdown.md): one stacked bar per path length k, its height the
// length's fraction of the measurement, its segments the classes of that length coloured as in
// the legend (the ten classes carrying the most energy; the rest grey).
#include <string>

#include "integrator/breakdown.h"

namespace omega {

// Writes a PNG (or whatever OIIO writes for the extension) to `path`; throws std::runtime_error.
void write_breakdown_chart(const BreakdownReport& r, const std::string& path);

}  // namespace omega
