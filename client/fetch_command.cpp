// `omega fetch JOB -o OUT.exr`: writes the job's current image once (atomic replace).
#include <fmt/format.h>

#include <cstdio>

#include "job_commands.h"
#include "film/film.h"
#include "remote_common.h"

namespace omega::client {

namespace proto = omega::protocol;

int run_fetch(const JobArgs& a) {
    return guarded([&] {
        Connection c = connect_to(a.host);
        proto::Fetch f{c.next_id(), *a.job};
        auto img = c.expect<proto::Image>(c.request(proto::encode(f), f.id));
        c.close();
        if (img.exr.size() < 4 || img.exr.compare(0, 4, "\x76\x2f\x31\x01") != 0)
            throw ClientError(kExitInternal, fmt::format("job {}: the daemon sent an image that is not an EXR file", *a.job));
        const std::string out = a.output.empty() ? fmt::format("job-{}.exr", *a.job) : a.output;
        write_file_atomic(out, std::span(reinterpret_cast<const uint8_t*>(img.exr.data()), img.exr.size()));
        std::printf("%s: %ux%u, pass %llu, %llu spp\n", out.c_str(), img.width, img.height,
                    (unsigned long long)img.pass, (unsigned long long)img.spp);
        return kExitOk;
    });
}

}  // namespace omega::client
