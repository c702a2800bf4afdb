#pragma once
// `omega render --breakdown`'s files: the report as CSV and as a chart, next to the EXR.
#include <string>

#include "integrator/breakdown.h"

namespace omega {

// NAME.breakdown.csv (or `csv_path`) and NAME.breakdown.png beside `exr_path`. Returns the
// process exit code: 0, or 2 when a file cannot be written (the message is printed).
int write_breakdown_files(const BreakdownReport& r, const std::string& exr_path, const std::string& csv_path);
// The default CSV and chart paths for an EXR path: OUT.exr -> OUT.breakdown.csv / .png.
std::string breakdown_path(const std::string& exr_path, const std::string& ext);

}  // namespace omega
