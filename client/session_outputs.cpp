#include "session_outputs.h"

#include <fmt/format.h>

#include "film/aov_film.h"

namespace omega {

const std::vector<AovFilm>& session_aov_films(const RenderSession& session) {
    static const std::vector<AovFilm> kNone;
    return session.aovs() ? session.aovs()->films() : kNone;
}

std::optional<BreakdownReport> add_session_outputs(const RenderSession& session, long long first, long long end,
                                                   bool part, ExrMeta& meta) {
    append_aov_layers(session_aov_films(session), meta);
    const BreakdownCollector* bc = session.breakdown();
    if (!bc) return std::nullopt;
    BreakdownReport report = bc->report();
    meta.attributes["omega.breakdown"] = breakdown_csv(report);
    meta.attributes["omega.breakdown_samples"] = fmt::format("{}:{}", first, end);
    if (part) meta.attributes["omega.breakdown_state"] = breakdown_state_text({bc->region_name(), bc->max_length(), bc->stats()});
    return report;
}

}  // namespace omega
