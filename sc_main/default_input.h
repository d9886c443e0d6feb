// The input rbcd-sim runs with neither --trace nor --scene.
#pragma once
#include <memory>

#include "common/fragment.h"
#include "io/trace_reader.h"

namespace rbcd {

std::unique_ptr<FragmentSource> open_default_input(const TraceLimits& limits);

} // namespace rbcd
