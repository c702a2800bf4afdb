#pragma once
// What the scene's path classes (pathspace/classify.h) say about light path expressions: an AOV
// whose expression matches no path the scene can produce, or only paths that no local sampling
// strategy (Veach, Theorem 8.3) or not this integrator can sample, stays black; the user is told
// why, in full-path notation.
#include <string>
#include <vector>

#include "pathspace/classify.h"
#include "pathspace/lpe.h"

namespace omega {

// One warning per AOV that can only render black. Called once per render on the thread that
// prepares it.
std::vector<std::string> aov_warnings(const Scene& scene, const LpeSet& aovs, IntegratorType integrator);

}  // namespace omega
