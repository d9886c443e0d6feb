#include "rbcd/io/prefetch_source.h"

#include <utility>

namespace rbcd {

PrefetchSource::PrefetchSource(std::unique_ptr<FragmentSource> inner, std::size_t depth)
    : inner_(std::move(inner)), ring_(depth < 2 ? 2 : depth), resume_(ring_.size() / 2) {
    thread_ = std::thread([this] { produce(); });
}

PrefetchSource::~PrefetchSource() {
    {
        std::lock_guard<std::mutex> lock(m_);
        stop_ = true;
    }
    not_full_.notify_all();
    thread_.join();
}

void PrefetchSource::produce() {
    std::size_t tail = 0;
    for (;;) {
        {
            // A full ring waits until the simulation has taken half of it:
            // waking per tile cost a context switch each on both threads.
            std::unique_lock<std::mutex> lock(m_);
            if (count_ == ring_.size()) not_full_.wait(lock, [&] { return stop_ || count_ <= resume_; });
            if (stop_) return;
        }
        // The slot at `tail` is the producer's alone until count_ covers it.
        Slot& s = ring_[tail];
        bool last = false;
        try {
            s.error = nullptr;
            s.ev = inner_->next(s.tile);
            last = s.ev == Event::End;
        } catch (...) {
            s.error = std::current_exception();
            s.ev = Event::End;
            last = true;
        }
        {
            std::lock_guard<std::mutex> lock(m_);
            ++count_;
        }
        not_empty_.notify_one();
        if (last) return;
        tail = (tail + 1) % ring_.size();
    }
}

FragmentSource::Event PrefetchSource::next(Tile& tile) {
    Slot* s;
    {
        std::unique_lock<std::mutex> lock(m_);
        not_empty_.wait(lock, [&] { return count_ > 0; });
        s = &ring_[head_];
    }
    if (s->error) std::rethrow_exception(s->error);   // stays: later calls see it again
    const Event ev = s->ev;
    if (ev == Event::End) return ev;                  // stays too: End is final
    if (ev == Event::Tile) std::swap(tile, s->tile);  // the caller's old storage goes back for reuse
    else tile.frame = s->tile.frame;
    bool wake;
    {
        std::lock_guard<std::mutex> lock(m_);
        head_ = (head_ + 1) % ring_.size();
        wake = --count_ == resume_;
    }
    if (wake) not_full_.notify_one();
    return ev;
}

} // namespace rbcd
