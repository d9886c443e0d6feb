// CollisionSink that writes the --collisions text file (formats.md).
#pragma once
#include <string>

#include "rbcd/hw/collision_sink.h"
#include "rbcd/io/collision_format.h"
#include "rbcd/common/output_file.h"

namespace rbcd {

class CollisionFileSink final : public CollisionSink {
public:
    explicit CollisionFileSink(OutputFile& out) : out_(out) { buf_ = kCollisionsMagic; }
    void frame(std::uint64_t n) override { append_frame_line(buf_, n); spill(); }
    void hit(const HitRecord& h) override { append_hit_line(buf_, h); spill(); }
    void overflow(const OverflowRecord& o) override { append_overflow_line(buf_, o); spill(); }
    void finish() { out_.write(buf_); buf_.clear(); }

private:
    void spill() {
        if (buf_.size() >= (1u << 16)) { out_.write(buf_); buf_.clear(); }
    }
    OutputFile& out_;
    std::string buf_;
};

} // namespace rbcd
