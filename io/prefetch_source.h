// Reads another source a few tiles ahead in a thread of its own, so that
// parsing a trace (about a third of a run's time) overlaps the simulation on
// a second core. The stream, its errors and their order are exactly the
// inner source's: an error is raised at the tile where the inner source
// raised it. Memory is bounded by `depth` tiles.
//
//   PrefetchSource src(std::make_unique<TraceReader>(path, limits));
//   while (src.next(tile) != FragmentSource::Event::End) ...
//
// Only for sources that nothing else touches while the run goes on (a trace
// reader); the scene source hands images to the simulation and is not wrapped.
#pragma once
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "rbcd/common/fragment.h"

namespace rbcd {

class PrefetchSource final : public FragmentSource {
public:
    explicit PrefetchSource(std::unique_ptr<FragmentSource> inner, std::size_t depth = 16);
    ~PrefetchSource() override;
    PrefetchSource(const PrefetchSource&) = delete;
    PrefetchSource& operator=(const PrefetchSource&) = delete;

    const StreamHeader& header() const override { return inner_->header(); }
    Event next(Tile& tile) override;
    std::string name() const override { return inner_->name(); }

private:
    struct Slot {
        Event ev = Event::End;
        Tile tile;
        std::exception_ptr error;
    };
    void produce();

    std::unique_ptr<FragmentSource> inner_;
    std::vector<Slot> ring_;
    std::size_t head_ = 0, count_ = 0;
    std::size_t resume_;   // a full ring's producer resumes at this count
    bool stop_ = false;
    std::mutex m_;
    std::condition_variable not_empty_, not_full_;
    std::thread thread_;
};

} // namespace rbcd
