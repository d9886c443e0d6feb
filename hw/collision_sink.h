// Where the records the host reads back from memory go: the collisions file,
// a test's recorder, the image writer.
#pragma once
#include <cstdint>
#include <variant>
#include <vector>

#include "rbcd/common/records.h"

namespace rbcd {

class CollisionSink {
public:
    virtual ~CollisionSink() = default;
    virtual void frame(std::uint64_t n) = 0;
    virtual void hit(const HitRecord& h) = 0;
    virtual void overflow(const OverflowRecord& o) = 0;
};

// Keeps everything in memory, frame by frame (tests, the differential check).
class RecordingSink final : public CollisionSink {
public:
    using Record = std::variant<HitRecord, OverflowRecord>;
    struct Frame {
        std::uint64_t frame = 0;
        std::vector<Record> records;
    };
    void frame(std::uint64_t n) override { frames.push_back({n, {}}); }
    void hit(const HitRecord& h) override { frames.back().records.emplace_back(h); }
    void overflow(const OverflowRecord& o) override { frames.back().records.emplace_back(o); }
    std::vector<Frame> frames;
};

// Fans records out to several sinks.
class TeeSink final : public CollisionSink {
public:
    void add(CollisionSink* s) { sinks_.push_back(s); }
    void frame(std::uint64_t n) override { for (auto* s : sinks_) s->frame(n); }
    void hit(const HitRecord& h) override { for (auto* s : sinks_) s->hit(h); }
    void overflow(const OverflowRecord& o) override { for (auto* s : sinks_) s->overflow(o); }

private:
    std::vector<CollisionSink*> sinks_;
};

} // namespace rbcd
