// The platform's own configuration header. Its path, common/config.h, is also
// the name of one of rbcd's: rbcd installs and includes its headers as
// "rbcd/common/config.h", so the two never meet (the test suite builds this
// example with this folder ahead of rbcd's on the include path).
#pragma once
#include <cstdint>

namespace platform {
constexpr std::uint64_t kSramBase = 0x20000000;   // where the platform maps its memory
constexpr std::uint64_t kSramSize = 1 << 20;
}  // namespace platform
