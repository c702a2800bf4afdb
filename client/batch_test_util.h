#pragma once
// Test helper shared by batch_test.cpp and slurm_batch_test.cpp.
#include <gtest/gtest.h>

#include <string>

#include "batch_command.h"
#include "client_error.h"
#include "test_fake_daemon.h"

namespace omega::client::test {

// The message parse_manifest gives for `manifest` (written to m.yaml in d), without the path
// prefix; "(accepted)" when it parses. A refusal must carry the bad-input exit code.
inline std::string parse_error(const TempDir& d, const std::string& manifest) {
    const auto p = d.write("m.yaml", manifest);
    try {
        parse_manifest(p.string());
    } catch (const ClientError& e) {
        EXPECT_EQ(e.exit_code(), kExitBadInput);
        return std::string(e.what()).substr(p.string().size());
    }
    return "(accepted)";
}

}  // namespace omega::client::test
