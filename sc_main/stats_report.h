// The --stats JSON document and the end-of-run summary on stdout.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "hw/rbcd_system.h"

namespace rbcd {

struct RunInfo {
    std::string input;        // trace path or scene name
    double wall_seconds = 0;
};

nlohmann::json make_stats(const rbcd_system& sys, const RunInfo& info);
std::string make_summary(const nlohmann::json& stats);

} // namespace rbcd
