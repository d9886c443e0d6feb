// A fragment stream held in memory: for tests, the differential test and the
// model-only benchmark (no parsing cost).
#pragma once
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "rbcd/common/fragment.h"

namespace rbcd {

class MemorySource final : public FragmentSource {
public:
    struct Item {
        bool is_frame;        // true: frame marker (tile.frame is its number)
        Tile tile;
    };
    explicit MemorySource(StreamHeader h, std::string name = "<memory>") : h_(h), name_(std::move(name)) {}

    void add_frame(std::uint64_t n) { items_.push_back({true, Tile{}}); items_.back().tile.frame = n; }
    void add_tile(Tile t) { items_.push_back({false, std::move(t)}); }
    // Drains another source fully into memory.
    void read_all(FragmentSource& src) {
        Tile t;
        for (;;) {
            auto ev = src.next(t);
            if (ev == Event::End) break;
            if (ev == Event::Frame) add_frame(t.frame); else add_tile(t);
        }
    }
    void rewind() { pos_ = 0; }
    std::size_t size() const { return items_.size(); }
    const std::vector<Item>& items() const { return items_; }

    const StreamHeader& header() const override { return h_; }
    StreamHeader& mutable_header() { return h_; }
    Event next(Tile& tile) override {
        if (pos_ >= items_.size()) return Event::End;
        const Item& it = items_[pos_++];
        if (it.is_frame) { tile.frame = it.tile.frame; return Event::Frame; }
        tile = it.tile;   // the vectors' capacity is reused
        return Event::Tile;
    }
    std::string name() const override { return name_; }

private:
    StreamHeader h_;
    std::string name_;
    std::vector<Item> items_;
    std::size_t pos_ = 0;
};

} // namespace rbcd
