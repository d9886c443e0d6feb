// Streaming reader of .rbt fragment traces (formats.md), plain or gzip.
// Holds one tile in memory at a time, so memory does not grow with the trace.
#pragma once
#include <memory>
#include <string>

#include "common/fragment.h"

namespace rbcd {

// What the unit accepts; the trace is checked against it while it is read.
struct TraceLimits {
    unsigned tile_w = 16, tile_h = 16;   // must equal the trace's tile_size
    unsigned id_bits = 7;                // object ids must fit
};

class TraceReader final : public FragmentSource {
public:
    // Reads the magic and header records. Throws InputError ("file:line: ...")
    // on malformed input or when the file cannot be opened ("file: cannot open: ...").
    TraceReader(const std::string& path, const TraceLimits& limits);
    ~TraceReader() override;
    const StreamHeader& header() const override;
    Event next(Tile& tile) override;
    std::string name() const override;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace rbcd
