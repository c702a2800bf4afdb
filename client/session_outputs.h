#pragma once
// What a finished render session adds to the EXR it is written to, the same for `omega render`
// and `omega worker`: the light path expression layers (pass session_aov_films() on to
// write_partial_exr, whose state channels merge exactly) and the path-class breakdown. A part
// (--samples A:B, a worker's unit) also carries the breakdown's exact sums, which `omega merge`
// and omegad's unit fold add up to one render's breakdown.
#include <optional>
#include <vector>

#include "film/aov_film.h"
#include "film/film.h"
#include "integrator/breakdown.h"
#include "integrator/render_session.h"

namespace omega {

const std::vector<AovFilm>& session_aov_films(const RenderSession& session);

// Samples [first, end) are what the session rendered. Returns the breakdown's report when the
// session has one (the caller prints it or writes its files).
std::optional<BreakdownReport> add_session_outputs(const RenderSession& session, long long first, long long end,
                                                   bool part, ExrMeta& meta);

}  // namespace omega
