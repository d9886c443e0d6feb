// The platform's own configuration header. Its path, common/config.h, is also
// the name of one of rbcd's: rbcd installs and includes its headers as
// "rbcd/common/config.h", so the two never meet (the test suite builds this
// example with this folder ahead of rbcd's on the include path).
#pragma once
#include <cstdint>

namespace platform {
constexpr std::uint64_t kSramBase = 0x120000000;  // where the platform maps its memory: above 4 GiB
constexpr std::uint64_t kSramSize = 1 << 20;
// The memory's latency, not a whole number of unit cycles (16.4 at 400 MHz).
constexpr unsigned kSramLatencyPs = 41000;
// Each unit's output regions, as this platform maps them inside the sram.
constexpr std::uint64_t kUnitRegionOffset[2] = {0x1000, 0x40000};
}  // namespace platform
