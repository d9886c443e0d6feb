#include "rbcd/io/read_ahead.h"

#include <algorithm>
#include <cstring>

namespace rbcd {

ReadAhead::ReadAhead(GzipStream& in, std::size_t chunk, std::size_t depth)
    : in_(in), ring_(std::max<std::size_t>(depth, 2)) {
    for (auto& c : ring_) c.bytes.resize(std::max<std::size_t>(chunk, 1));
    thread_ = std::thread([this] { produce(); });
}

ReadAhead::~ReadAhead() {
    {
        std::lock_guard<std::mutex> lock(m_);
        stop_ = true;
    }
    not_full_.notify_all();
    if (thread_.joinable()) thread_.join();
}

void ReadAhead::produce() {
    std::size_t tail = 0;
    for (;;) {
        {
            std::unique_lock<std::mutex> lock(m_);
            not_full_.wait(lock, [&] { return stop_ || count_ < ring_.size(); });
            if (stop_) return;
        }
        // The slot at `tail` is the thread's alone until count_ covers it.
        Chunk& c = ring_[tail];
        c.got = in_.read(c.bytes.data(), c.bytes.size());
        const bool last = c.got <= 0;
        {
            std::lock_guard<std::mutex> lock(m_);
            ++count_;
        }
        not_empty_.notify_one();
        if (last) return;
        tail = (tail + 1) % ring_.size();
    }
}

long ReadAhead::read(char* dst, std::size_t n) {
    Chunk* c;
    {
        std::unique_lock<std::mutex> lock(m_);
        not_empty_.wait(lock, [&] { return count_ > 0; });
        c = &ring_[head_];
    }
    if (c->got <= 0) {
        // The end or the error, which stays for later calls; the thread has
        // returned, so its observer calls are over.
        if (thread_.joinable()) thread_.join();
        if (c->got < 0) error_ = in_.error();
        return c->got;
    }
    const std::size_t k = std::min(n, static_cast<std::size_t>(c->got) - pos_);
    std::memcpy(dst, c->bytes.data() + pos_, k);
    pos_ += k;
    if (pos_ == static_cast<std::size_t>(c->got)) {
        pos_ = 0;
        {
            std::lock_guard<std::mutex> lock(m_);
            head_ = (head_ + 1) % ring_.size();
            --count_;
        }
        not_full_.notify_one();
    }
    return static_cast<long>(k);
}

} // namespace rbcd
