// Unit tests of the reference model (ref/reference_model.h). Every expectation
// is worked out by hand from rbcd-contract.md; the comment above each one is
// the derivation, so that a failure can be judged against the contract and not
// against the code.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "rbcd/common/errors.h"
#include "rbcd/io/memory_source.h"
#include "rbcd/ref/reference_model.h"

using namespace rbcd;
using namespace rbcd::ref;

namespace {

Fragment frag(std::uint32_t x, std::uint32_t y, std::uint32_t depth, std::uint32_t id, char face,
              bool culled = false) {
    Fragment f;
    f.x = x;
    f.y = y;
    f.depth = depth;
    f.id = id;
    f.facing = face == 'B' ? Facing::Back : Facing::Front;
    f.culled = culled;
    return f;
}

Element elem(std::uint32_t dq, std::uint32_t id, char face) {
    Element e;
    e.dq = dq;
    e.id = id;
    e.facing = face == 'B' ? Facing::Back : Facing::Front;
    return e;
}

// Records as collision-file lines: readable in a failure message.
std::string text(const std::vector<RefRecord>& recs) {
    std::string s;
    for (const auto& r : recs) {
        if (const auto* h = std::get_if<HitRecord>(&r)) {
            s += "hit " + std::to_string(h->x) + " " + std::to_string(h->y) + " " + std::to_string(h->id_a) + " " +
                 std::to_string(h->id_b) + " " + std::to_string(h->dq) + "\n";
        } else {
            const auto& o = std::get<OverflowRecord>(r);
            s += "overflow " + std::to_string(o.col) + " " + std::to_string(o.row) + " " + std::to_string(o.lists) +
                 " " + std::to_string(o.dropped) + "\n";
        }
    }
    return s;
}

// "id:dq:F" per element, front to back.
std::string show(const std::vector<Element>& list) {
    std::string s;
    for (const auto& e : list) {
        if (!s.empty()) s += ' ';
        s += std::to_string(e.id) + ":" + std::to_string(e.dq) + ":" + (e.facing == Facing::Back ? "B" : "F");
    }
    return s;
}

struct TileRun {
    std::string out;
    RefCounts counts;
};

TileRun run_tile(const RefConfig& cfg, const std::vector<Fragment>& frags, std::uint32_t col = 0,
                 std::uint32_t row = 0) {
    Tile t;
    t.col = col;
    t.row = row;
    t.frags = frags;
    std::vector<RefRecord> recs;
    TileRun r;
    reference_tile(cfg, t, recs, r.counts);
    r.out = text(recs);
    return r;
}

Tile make_tile(std::uint64_t frame, std::uint32_t col, std::uint32_t row, std::vector<Fragment> frags) {
    Tile t;
    t.frame = frame;
    t.col = col;
    t.row = row;
    t.frags = std::move(frags);
    return t;
}

constexpr std::uint32_t A = 1, B = 2, C = 3;

} // namespace

// ---------------------------------------------------------------- sorter

TEST_CASE("insert into a non-full list lands at every position", "[ref][sort]") {
    // Base list 10,20,30 (ids 1,2,3, all front); M = 8 so nothing drops.
    const std::vector<Element> base = {elem(10, 1, 'F'), elem(20, 2, 'F'), elem(30, 3, 'F')};
    struct Case {
        std::uint32_t dq;
        const char* expect;
    };
    // Position = count of keys <= new key: 5 -> 0, 15 -> 1, 25 -> 2, 35 -> 3.
    const Case cases[] = {
        {5, "9:5:F 1:10:F 2:20:F 3:30:F"},
        {15, "1:10:F 9:15:F 2:20:F 3:30:F"},
        {25, "1:10:F 2:20:F 9:25:F 3:30:F"},
        {35, "1:10:F 2:20:F 3:30:F 9:35:F"},
        // An equal key goes after the equal one (stable in arrival order).
        {20, "1:10:F 2:20:F 9:20:F 3:30:F"},
    };
    for (const auto& c : cases) {
        for (TiePolicy tie : {TiePolicy::FrontFirst, TiePolicy::Arrival}) {
            auto list = base;
            CHECK(insert_element(list, elem(c.dq, 9, 'F'), 8, tie) == 0);
            CHECK(show(list) == c.expect);
        }
    }
    std::vector<Element> empty;
    CHECK(insert_element(empty, elem(7, 4, 'B'), 8, TiePolicy::FrontFirst) == 0);
    CHECK(show(empty) == "4:7:B");
}

TEST_CASE("insert into a full list: position M drops the new element", "[ref][sort][overflow]") {
    // M = 3, list 10,20,30 full.
    std::vector<Element> list = {elem(10, 1, 'F'), elem(20, 2, 'F'), elem(30, 3, 'F')};
    // 40 > every key: position 3 = M, dropped, list unchanged.
    CHECK(insert_element(list, elem(40, 9, 'F'), 3, TiePolicy::FrontFirst) == 1);
    CHECK(show(list) == "1:10:F 2:20:F 3:30:F");
    // Equal to the last key: it goes after the equal one, so position 3 = M again.
    CHECK(insert_element(list, elem(30, 9, 'F'), 3, TiePolicy::FrontFirst) == 1);
    CHECK(show(list) == "1:10:F 2:20:F 3:30:F");
    // front_first: a back face at dq 30 sorts after the front at 30: position 3, dropped.
    CHECK(insert_element(list, elem(30, 9, 'B'), 3, TiePolicy::FrontFirst) == 1);
    CHECK(show(list) == "1:10:F 2:20:F 3:30:F");
}

TEST_CASE("insert into a full list: otherwise the last element is shifted out", "[ref][sort][overflow]") {
    const std::vector<Element> base = {elem(10, 1, 'F'), elem(20, 2, 'F'), elem(30, 3, 'F')};
    struct Case {
        std::uint32_t dq;
        const char* expect;
    };
    const Case cases[] = {
        {5, "9:5:F 1:10:F 2:20:F"},     // position 0
        {15, "1:10:F 9:15:F 2:20:F"},   // position 1
        {25, "1:10:F 2:20:F 9:25:F"},   // position 2 = M-1: the old last (30) goes
        {20, "1:10:F 2:20:F 9:20:F"},   // equal to 20: position 2
    };
    for (const auto& c : cases) {
        auto list = base;
        CHECK(insert_element(list, elem(c.dq, 9, 'F'), 3, TiePolicy::FrontFirst) == 1);
        CHECK(show(list) == c.expect);
    }
    // front_first: a front face at dq 30 sorts before the back face at 30, which is shifted out.
    std::vector<Element> list = {elem(10, 1, 'F'), elem(20, 2, 'F'), elem(30, 3, 'B')};
    CHECK(insert_element(list, elem(30, 9, 'F'), 3, TiePolicy::FrontFirst) == 1);
    CHECK(show(list) == "1:10:F 2:20:F 9:30:F");
    // arrival: the same front face has an equal key, position 3 = M: dropped.
    list = {elem(10, 1, 'F'), elem(20, 2, 'F'), elem(30, 3, 'B')};
    CHECK(insert_element(list, elem(30, 9, 'F'), 3, TiePolicy::Arrival) == 1);
    CHECK(show(list) == "1:10:F 2:20:F 3:30:B");
}

TEST_CASE("M = 1: every second element of a pixel overflows", "[ref][sort][overflow]") {
    std::vector<Element> list;
    CHECK(insert_element(list, elem(50, 1, 'F'), 1, TiePolicy::FrontFirst) == 0);
    // Nearer: position 0 < M, the old one is shifted out.
    CHECK(insert_element(list, elem(40, 2, 'F'), 1, TiePolicy::FrontFirst) == 1);
    CHECK(show(list) == "2:40:F");
    // Farther: position 1 = M, dropped.
    CHECK(insert_element(list, elem(60, 3, 'F'), 1, TiePolicy::FrontFirst) == 1);
    CHECK(show(list) == "2:40:F");
}

TEST_CASE("ties: front_first puts a front face before an equal back face, arrival keeps arrival order",
          "[ref][sort][tie]") {
    // Back face of 1 at dq 10 arrives first, then a front face of 2 at dq 10.
    std::vector<Element> ff = {elem(10, 1, 'B')};
    insert_element(ff, elem(10, 2, 'F'), 8, TiePolicy::FrontFirst);
    CHECK(show(ff) == "2:10:F 1:10:B");   // key (10,0) < (10,1): position 0
    std::vector<Element> arr = {elem(10, 1, 'B')};
    insert_element(arr, elem(10, 2, 'F'), 8, TiePolicy::Arrival);
    CHECK(show(arr) == "1:10:B 2:10:F");  // keys equal: after the equal one

    // Front first, then back at the same dq: both policies keep the front first.
    for (TiePolicy tie : {TiePolicy::FrontFirst, TiePolicy::Arrival}) {
        std::vector<Element> l = {elem(10, 1, 'F')};
        insert_element(l, elem(10, 2, 'B'), 8, tie);
        CHECK(show(l) == "1:10:F 2:10:B");
    }
    // Equal keys of the same facing stay in arrival order under both.
    for (TiePolicy tie : {TiePolicy::FrontFirst, TiePolicy::Arrival}) {
        std::vector<Element> l = {elem(10, 1, 'B'), elem(10, 2, 'B')};
        insert_element(l, elem(10, 3, 'B'), 8, tie);
        CHECK(show(l) == "1:10:B 2:10:B 3:10:B");
    }
    // front_first: a front face goes after every front and before every back at its dq.
    std::vector<Element> l = {elem(10, 1, 'F'), elem(10, 2, 'B'), elem(10, 3, 'B')};
    insert_element(l, elem(10, 4, 'F'), 8, TiePolicy::FrontFirst);
    CHECK(show(l) == "1:10:F 4:10:F 2:10:B 3:10:B");
}

TEST_CASE("touching surfaces are contact under front_first only", "[ref][tie]") {
    // A spans 100..200, B spans 200..300: B's front and A's back share dq 200.
    // Arrival order: A F, A B, B F, B B.
    const std::vector<Fragment> fr = {frag(0, 0, 100, A, 'F'), frag(0, 0, 200, A, 'B'), frag(0, 0, 200, B, 'F'),
                                      frag(0, 0, 300, B, 'B')};
    RefConfig cfg;
    // front_first: list A F(100), B F(200), A B(200), B B(300). A back: B above -> hit (1,2,200).
    CHECK(run_tile(cfg, fr).out == "hit 0 0 1 2 200\n");
    // arrival: B F(200) arrived after A B(200), so goes after it: A F, A B, B F, B B -> no hit.
    cfg.tie = TiePolicy::Arrival;
    CHECK(run_tile(cfg, fr).out == "");
    // arrival with B's front arriving first: B F, A F, A B, B B -> list A F, B F, A B, B B -> hit.
    const std::vector<Fragment> fr2 = {frag(0, 0, 200, B, 'F'), frag(0, 0, 100, A, 'F'), frag(0, 0, 200, A, 'B'),
                                       frag(0, 0, 300, B, 'B')};
    CHECK(run_tile(cfg, fr2).out == "hit 0 0 1 2 200\n");
}

TEST_CASE("raw hit order reveals the list order after inserts at every position", "[ref][sort]") {
    // Pixel (3,2). A F at 0 is the stack's bottom and A B at 1000 the list's end, so A's
    // back face reports every other front face in list order (stack bottom to top).
    // After A F, A B the fronts arrive as 500 (id 5) -> position 1, 300 -> 1 (before 500),
    // 700 -> 3 (after 500), 400 -> 2, 600 -> 4, 200 -> 1.
    const std::vector<Fragment> fr = {frag(3, 2, 0, A, 'F'),    frag(3, 2, 1000, A, 'B'), frag(3, 2, 500, 5, 'F'),
                                      frag(3, 2, 300, 3, 'F'),  frag(3, 2, 700, 7, 'F'),  frag(3, 2, 400, 4, 'F'),
                                      frag(3, 2, 600, 6, 'F'),  frag(3, 2, 200, 2, 'F')};
    RefConfig cfg;
    const auto r = run_tile(cfg, fr);
    // List (8 = M, full but not overflowing): A F, 2, 3, 4, 5, 6, 7, A B.
    CHECK(r.out ==
          "hit 3 2 1 2 1000\nhit 3 2 1 3 1000\nhit 3 2 1 4 1000\nhit 3 2 1 5 1000\nhit 3 2 1 6 1000\nhit 3 2 1 7 1000\n");
    CHECK(r.counts.overflows == 0);
}

// ---------------------------------------------------------------- quantization

TEST_CASE("quantize_depth keeps the top z_bits or widens", "[ref][quant]") {
    CHECK(quantize_depth(0x123456, 24, 8) == 0x12);        // z < depth_bits
    CHECK(quantize_depth(0x123456, 24, 24) == 0x123456);   // equal
    CHECK(quantize_depth(0x1234, 16, 24) == 0x123400);     // z > depth_bits: widened
    CHECK(quantize_depth(0xffffffffu, 32, 32) == 0xffffffffu);
    CHECK(quantize_depth(0xffffffffu, 32, 1) == 1);        // shift by 31
    CHECK(quantize_depth(1, 1, 32) == 0x80000000u);        // shift by 31 the other way
    CHECK(quantize_depth(0, 24, 1) == 0);
}

TEST_CASE("hit dq is the back face's quantized depth", "[ref][quant]") {
    // Figure 5 case 2: A's back face (0x345678) is the one that finds B above A.
    const std::vector<Fragment> fr = {frag(0, 0, 0x123456, A, 'F'), frag(0, 0, 0x234567, B, 'F'),
                                      frag(0, 0, 0x345678, A, 'B'), frag(0, 0, 0xABCDEF, B, 'B')};
    RefConfig cfg;
    cfg.z_bits = 8;
    CHECK(run_tile(cfg, fr).out == "hit 0 0 1 2 52\n");          // 0x34
    cfg.z_bits = 24;
    CHECK(run_tile(cfg, fr).out == "hit 0 0 1 2 3430008\n");     // 0x345678
    cfg.z_bits = 32;
    CHECK(run_tile(cfg, fr).out == "hit 0 0 1 2 878082048\n");   // 0x34567800
    cfg.z_bits = 20;
    CHECK(run_tile(cfg, fr).out == "hit 0 0 1 2 214375\n");      // 0x34567
}

TEST_CASE("quantization can collapse distinct depths into one dq and create a contact", "[ref][quant]") {
    // A: 0x100000..0x10F000, B starts at 0x10FFFF: apart at 24 bits.
    const std::vector<Fragment> fr = {frag(0, 0, 0x100000, A, 'F'), frag(0, 0, 0x10F000, A, 'B'),
                                      frag(0, 0, 0x10FFFF, B, 'F'), frag(0, 0, 0x10FFFF, B, 'B')};
    RefConfig cfg;
    CHECK(run_tile(cfg, fr).out == "");
    // z_bits = 8: every dq is 0x10. front_first keys: A F (16,0), A B (16,1), B F (16,0), B B (16,1).
    // B F inserts after A F, before A B -> A F, B F, A B, B B: A's back face sees B -> hit dq 16.
    cfg.z_bits = 8;
    CHECK(run_tile(cfg, fr).out == "hit 0 0 1 2 16\n");
    // Under arrival the collapsed keys are all equal: arrival order, no hit.
    cfg.tie = TiePolicy::Arrival;
    CHECK(run_tile(cfg, fr).out == "");
}

TEST_CASE("32-bit depths with z_bits = 32", "[ref][quant]") {
    RefConfig cfg;
    cfg.depth_bits = 32;
    cfg.z_bits = 32;
    const std::vector<Fragment> fr = {frag(0, 0, 0x80000000u, A, 'F'), frag(0, 0, 0xfffffff0u, B, 'F'),
                                      frag(0, 0, 0xfffffffeu, A, 'B'), frag(0, 0, 0xffffffffu, B, 'B')};
    CHECK(run_tile(cfg, fr).out == "hit 0 0 1 2 4294967294\n");
}

// ---------------------------------------------------------------- z-overlap test

TEST_CASE("Figure 5 case 1: disjoint intervals give no hit", "[ref][stack][fig5]") {
    // A F, A B, B F, B B: push A; A back matches A with nothing above; push B; B back likewise.
    const auto r = run_tile(RefConfig{}, {frag(5, 6, 100, A, 'F'), frag(5, 6, 200, A, 'B'), frag(5, 6, 300, B, 'F'),
                                         frag(5, 6, 400, B, 'B')});
    CHECK(r.out == "");
    CHECK(r.counts.orphan_back_faces == 0);
    CHECK(r.counts.hits == 0);
}

TEST_CASE("Figure 5 case 2: overlapping intervals give one hit", "[ref][stack][fig5]") {
    // Stack A, B. A back (dq 300): m = 0, B above -> hit (1,2,300). B back: m = 1, nothing above.
    const auto r = run_tile(RefConfig{}, {frag(5, 6, 100, A, 'F'), frag(5, 6, 200, B, 'F'), frag(5, 6, 300, A, 'B'),
                                         frag(5, 6, 400, B, 'B')});
    CHECK(r.out == "hit 5 6 1 2 300\n");
    CHECK(r.counts.hits == 1);
}

TEST_CASE("Figure 5 case 3: B nested inside A is a hit reported by A's back face", "[ref][stack][fig5]") {
    // Stack A, B. B back (300): m = 1, nothing above; matched[1] = 1 (B stays).
    // A back (400): m = 0; B above, matched but still there -> hit (1,2,400).
    const auto r = run_tile(RefConfig{}, {frag(5, 6, 100, A, 'F'), frag(5, 6, 200, B, 'F'), frag(5, 6, 300, B, 'B'),
                                         frag(5, 6, 400, A, 'B')});
    CHECK(r.out == "hit 5 6 1 2 400\n");
}

TEST_CASE("arrival order does not matter, only the sorted order", "[ref][stack][fig5]") {
    // Case 3's fragments in reverse arrival order.
    const auto r = run_tile(RefConfig{}, {frag(5, 6, 400, A, 'B'), frag(5, 6, 300, B, 'B'), frag(5, 6, 200, B, 'F'),
                                         frag(5, 6, 100, A, 'F')});
    CHECK(r.out == "hit 5 6 1 2 400\n");
}

TEST_CASE("nested intervals of one object give no hit", "[ref][stack]") {
    // Stack A, A. First A back: m = 0; entry 1 has id A = c -> no hit. Second: m = 1.
    const auto r = run_tile(RefConfig{}, {frag(0, 0, 100, A, 'F'), frag(0, 0, 200, A, 'F'), frag(0, 0, 300, A, 'B'),
                                         frag(0, 0, 400, A, 'B')});
    CHECK(r.out == "");
    CHECK(r.counts.orphan_back_faces == 0);
}

TEST_CASE("entries with the back face's id are skipped but others above still hit", "[ref][stack]") {
    // Stack A, B, A. A back (400): m = 0; entry 1 (B) -> hit, entry 2 (A) skipped.
    // B back (500): m = 1; entry 2 (A, unmatched) -> hit (1,2,500).
    // A back (600): m = 2; nothing above.
    const auto r = run_tile(RefConfig{}, {frag(0, 0, 100, A, 'F'), frag(0, 0, 200, B, 'F'), frag(0, 0, 300, A, 'F'),
                                         frag(0, 0, 400, A, 'B'), frag(0, 0, 500, B, 'B'), frag(0, 0, 600, A, 'B')});
    CHECK(r.out == "hit 0 0 1 2 400\nhit 0 0 1 2 500\n");
}

TEST_CASE("orphan back faces are counted and change nothing else", "[ref][stack]") {
    // Back face first (inverted interval): stack empty -> orphan; then push B.
    auto r = run_tile(RefConfig{}, {frag(0, 0, 300, B, 'F'), frag(0, 0, 100, B, 'B')});
    CHECK(r.out == "");
    CHECK(r.counts.orphan_back_faces == 1);
    // A lone back face.
    r = run_tile(RefConfig{}, {frag(0, 0, 300, C, 'B')});
    CHECK(r.counts.orphan_back_faces == 1);
    // Stack A, B; C back is an orphan and must not hit anything; A back then hits B.
    r = run_tile(RefConfig{}, {frag(0, 0, 100, A, 'F'), frag(0, 0, 200, B, 'F'), frag(0, 0, 250, C, 'B'),
                               frag(0, 0, 300, A, 'B')});
    CHECK(r.out == "hit 0 0 1 2 300\n");
    CHECK(r.counts.orphan_back_faces == 1);
}

TEST_CASE("a matched entry is kept but cannot be matched twice", "[ref][stack]") {
    // Stack A. A back (200): m = 0, matched. Second A back (300): no unmatched A -> orphan.
    // Then B F pushes above the matched A; B back (500): m = 1, nothing above.
    const auto r = run_tile(RefConfig{}, {frag(0, 0, 100, A, 'F'), frag(0, 0, 200, A, 'B'), frag(0, 0, 300, A, 'B'),
                                         frag(0, 0, 400, B, 'F'), frag(0, 0, 500, B, 'B')});
    CHECK(r.out == "");
    CHECK(r.counts.orphan_back_faces == 1);
    // A matched entry keeps its slot, and a later front face of the same object gets a new one.
    const auto r2 = run_tile(RefConfig{}, {frag(0, 0, 100, A, 'F'), frag(0, 0, 200, A, 'B'), frag(0, 0, 300, B, 'F'),
                                          frag(0, 0, 400, A, 'F'), frag(0, 0, 500, B, 'B'), frag(0, 0, 600, A, 'B')});
    // Walk: push A; A back (200): m=0, matched. push B (1). push A (2). B back (500): m = 1; entry 2 (A) -> hit 500.
    // A back (600): bottommost unmatched A is entry 2, nothing above.
    CHECK(r2.out == "hit 0 0 1 2 500\n");
}

TEST_CASE("FF-stack overflow drops the push and counts it", "[ref][stack][overflow]") {
    const std::vector<Fragment> fr = {frag(0, 0, 100, A, 'F'), frag(0, 0, 200, B, 'F'), frag(0, 0, 300, C, 'F'),
                                      frag(0, 0, 400, A, 'B'), frag(0, 0, 500, C, 'B')};
    RefConfig cfg;
    // T = 8: stack A, B, C. A back: hits B, C. C back: m = 2, nothing above.
    auto r = run_tile(cfg, fr);
    CHECK(r.out == "hit 0 0 1 2 400\nhit 0 0 1 3 400\n");
    CHECK(r.counts.stack_overflows == 0);
    // T = 2: C's push is dropped (1 stack overflow). A back: hits B only. C back: orphan.
    cfg.stack_depth = 2;
    r = run_tile(cfg, fr);
    CHECK(r.out == "hit 0 0 1 2 400\n");
    CHECK(r.counts.stack_overflows == 1);
    CHECK(r.counts.orphan_back_faces == 1);
    // T = 1: B and C dropped; A back finds nothing above; C back orphan.
    cfg.stack_depth = 1;
    r = run_tile(cfg, fr);
    CHECK(r.out == "");
    CHECK(r.counts.stack_overflows == 2);
    CHECK(r.counts.orphan_back_faces == 1);
}

TEST_CASE("a full stack stays full after a match: matched entries keep their slot", "[ref][stack][overflow]") {
    // T = 2: push A, push B, A back (300) hits B and matches A, C F (400) is still dropped.
    RefConfig cfg;
    cfg.stack_depth = 2;
    const auto r = run_tile(cfg, {frag(0, 0, 100, A, 'F'), frag(0, 0, 200, B, 'F'), frag(0, 0, 300, A, 'B'),
                                  frag(0, 0, 400, C, 'F'), frag(0, 0, 500, B, 'B')});
    // B back (500): m = 1, nothing above (C was never pushed).
    CHECK(r.out == "hit 0 0 1 2 300\n");
    CHECK(r.counts.stack_overflows == 1);
}

TEST_CASE("the stack is empty at the start of every list", "[ref][stack]") {
    // Pixel (0,0) leaves A unmatched; pixel (1,0) has only B F and A B: orphan there, no hit.
    const auto r = run_tile(RefConfig{}, {frag(0, 0, 100, A, 'F'), frag(1, 0, 200, B, 'F'), frag(1, 0, 300, A, 'B')});
    CHECK(r.out == "");
    CHECK(r.counts.orphan_back_faces == 1);
}

// ---------------------------------------------------------------- output, records, counts

TEST_CASE("hits are ordered row-major, then front to back, then bottom to top", "[ref][output]") {
    // Tile 8x4 at column 3, row 2: origin (24, 8). Pixel (25,8) has index 1, (24,9) index 8.
    // The fragments of (24,9) arrive first; (25,8) is still tested first.
    RefConfig cfg;
    cfg.tile_w = 8;
    cfg.tile_h = 4;
    const auto r = run_tile(cfg,
                            {frag(24, 9, 10, A, 'F'), frag(24, 9, 20, C, 'F'), frag(24, 9, 30, A, 'B'),
                             frag(25, 8, 10, A, 'F'), frag(25, 8, 20, B, 'F'), frag(25, 8, 30, A, 'B'),
                             frag(31, 11, 10, B, 'F'), frag(31, 11, 20, C, 'F'), frag(31, 11, 30, B, 'B')},
                            3, 2);
    CHECK(r.out == "hit 25 8 1 2 30\nhit 24 9 1 3 30\nhit 31 11 2 3 30\n");
}

TEST_CASE("output modes keep the first hit of a pair per pixel or per tile", "[ref][output]") {
    // Pixel (0,0): stack A, A, B. A back (40): m = 0, entry 1 is A (skip), entry 2 B -> (1,2,40).
    //   A back (50): m = 1, B above -> (1,2,50).
    // Pixel (1,0): stack A, C, B. A back (60): hits (1,3,60), (1,2,60). B back (70): m = 2, nothing.
    const std::vector<Fragment> fr = {frag(0, 0, 10, A, 'F'), frag(0, 0, 20, A, 'F'), frag(0, 0, 30, B, 'F'),
                                      frag(0, 0, 40, A, 'B'), frag(0, 0, 50, A, 'B'), frag(1, 0, 10, A, 'F'),
                                      frag(1, 0, 20, C, 'F'), frag(1, 0, 30, B, 'F'), frag(1, 0, 60, A, 'B'),
                                      frag(1, 0, 70, B, 'B')};
    RefConfig cfg;
    auto r = run_tile(cfg, fr);
    CHECK(r.out == "hit 0 0 1 2 40\nhit 0 0 1 2 50\nhit 1 0 1 3 60\nhit 1 0 1 2 60\n");
    CHECK(r.counts.hits == 4);
    cfg.output = OutputMode::Pixel;
    r = run_tile(cfg, fr);
    CHECK(r.out == "hit 0 0 1 2 40\nhit 1 0 1 3 60\nhit 1 0 1 2 60\n");
    CHECK(r.counts.hits == 3);
    cfg.output = OutputMode::Tile;
    r = run_tile(cfg, fr);
    CHECK(r.out == "hit 0 0 1 2 40\nhit 1 0 1 3 60\n");
    CHECK(r.counts.hits == 2);
}

TEST_CASE("tile output mode forgets pairs between tiles", "[ref][output]") {
    RefConfig cfg;
    cfg.output = OutputMode::Tile;
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    // Case 2 in tile (0,0) and again in tile (1,0): each tile writes its own first hit.
    src.add_tile(make_tile(0, 0, 0, {frag(2, 3, 10, A, 'F'), frag(2, 3, 20, B, 'F'), frag(2, 3, 30, A, 'B')}));
    src.add_tile(make_tile(0, 1, 0, {frag(18, 3, 10, A, 'F'), frag(18, 3, 20, B, 'F'), frag(18, 3, 30, A, 'B'),
                                     frag(19, 3, 10, A, 'F'), frag(19, 3, 20, B, 'F'), frag(19, 3, 35, A, 'B')}));
    const auto res = run_reference(cfg, src);
    REQUIRE(res.frames.size() == 1);
    CHECK(text(res.frames[0].records) == "hit 2 3 1 2 30\nhit 18 3 1 2 30\n");
    CHECK(res.counts.hits == 2);
}

TEST_CASE("overflow record: lists overflowed and fragments dropped, after the tile's hits", "[ref][overflow]") {
    RefConfig cfg;
    cfg.list_length = 2;
    // Tile column 2, row 1 (origin 32,16).
    // Pixel (32,16): A F 10, B F 20 fill it; A B 30 and B B 40 land at position 2 = M: 2 dropped.
    // Pixel (40,20): A F 30, A B 50, then B F 40 at position 1: A B shifted out, 1 dropped.
    // Pixel (47,31): A F 10, B B 20 fit: no overflow; B's back face is an orphan.
    // No list keeps a back face above another object's front: no hit.
    const auto r = run_tile(cfg,
                            {frag(32, 16, 10, A, 'F'), frag(32, 16, 20, B, 'F'), frag(32, 16, 30, A, 'B'),
                             frag(32, 16, 40, B, 'B'), frag(40, 20, 30, A, 'F'), frag(40, 20, 50, A, 'B'),
                             frag(40, 20, 40, B, 'F'), frag(47, 31, 10, A, 'F'), frag(47, 31, 20, B, 'B')},
                            2, 1);
    CHECK(r.out == "overflow 2 1 2 3\n");
    CHECK(r.counts.overflows == 3);
    CHECK(r.counts.orphan_back_faces == 1);
    CHECK(r.counts.fragments == 9);
}

TEST_CASE("overflow record follows the hits; a tile without overflow writes none", "[ref][overflow]") {
    RefConfig cfg;
    cfg.list_length = 3;
    // Pixel (0,0): A F 10, B F 20, A B 30, C F 5 -> C F at position 0 shifts A B out: list C F, A F, B F.
    //   No back face left: no hit. 1 dropped.
    // Pixel (1,0): A F 10, B F 20, A B 30 -> full, not overflowed: hit (1,2,30).
    // Pixel (2,0): A F 10, B F 20, A B 30, B B 40 -> B B at position 3 = M: dropped. Hit (1,2,30).
    auto r = run_tile(cfg, {frag(0, 0, 10, A, 'F'), frag(0, 0, 20, B, 'F'), frag(0, 0, 30, A, 'B'),
                            frag(0, 0, 5, C, 'F'), frag(1, 0, 10, A, 'F'), frag(1, 0, 20, B, 'F'),
                            frag(1, 0, 30, A, 'B'), frag(2, 0, 10, A, 'F'), frag(2, 0, 20, B, 'F'),
                            frag(2, 0, 30, A, 'B'), frag(2, 0, 40, B, 'B')});
    CHECK(r.out == "hit 1 0 1 2 30\nhit 2 0 1 2 30\noverflow 0 0 2 2\n");
    CHECK(r.counts.overflows == 2);
    // Exactly M fragments per list: full but nothing dropped, no record.
    r = run_tile(cfg, {frag(1, 0, 10, A, 'F'), frag(1, 0, 20, B, 'F'), frag(1, 0, 30, A, 'B')});
    CHECK(r.out == "hit 1 0 1 2 30\n");
    CHECK(r.counts.overflows == 0);
}

TEST_CASE("counts: fragments include culled ones, tiles include empty ones, frames include empty ones",
          "[ref][counts]") {
    RefConfig cfg;
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    // A culled fragment is processed like any other: case 2 with a culled B front still hits.
    src.add_tile(make_tile(0, 5, 3, {frag(80, 48, 100, A, 'F'), frag(80, 48, 200, B, 'F', true),
                                     frag(80, 48, 300, A, 'B', true), frag(80, 48, 400, B, 'B')}));
    src.add_tile(make_tile(0, 0, 0, {}));   // empty tile: counted, no records
    src.add_frame(1);                        // empty frame
    src.add_frame(2);
    src.add_tile(make_tile(2, 49, 29, {frag(799, 479, 7, C, 'B')}));
    const auto res = run_reference(cfg, src);
    REQUIRE(res.frames.size() == 3);
    CHECK(res.frames[0].frame == 0);
    CHECK(text(res.frames[0].records) == "hit 80 48 1 2 300\n");
    CHECK(res.frames[1].frame == 1);
    CHECK(res.frames[1].records.empty());
    CHECK(res.frames[2].frame == 2);
    CHECK(res.frames[2].records.empty());
    CHECK(res.counts.frames == 3);
    CHECK(res.counts.tiles == 3);
    CHECK(res.counts.fragments == 5);
    CHECK(res.counts.hits == 1);
    CHECK(res.counts.orphan_back_faces == 1);
    CHECK(res.counts.overflows == 0);
    CHECK(res.counts.stack_overflows == 0);
}

TEST_CASE("counts add up over tiles and frames", "[ref][counts]") {
    RefConfig cfg;
    cfg.list_length = 1;
    cfg.stack_depth = 1;
    cfg.output = OutputMode::Pixel;
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    // M = 1: pixel (0,0) gets 3 fragments, keeps the nearest (A F 10): 2 dropped.
    src.add_tile(make_tile(0, 0, 0, {frag(0, 0, 30, A, 'B'), frag(0, 0, 20, B, 'F'), frag(0, 0, 10, A, 'F')}));
    src.add_frame(1);
    // M = 1 again: one per pixel, so lone back faces are orphans: 2.
    src.add_tile(make_tile(1, 1, 1, {frag(16, 16, 5, A, 'B'), frag(17, 16, 5, B, 'B')}));
    const auto res = run_reference(cfg, src);
    REQUIRE(res.frames.size() == 2);
    CHECK(text(res.frames[0].records) == "overflow 0 0 1 2\n");
    CHECK(res.frames[1].records.empty());
    CHECK(res.counts.tiles == 2);
    CHECK(res.counts.fragments == 5);
    CHECK(res.counts.overflows == 2);
    CHECK(res.counts.orphan_back_faces == 2);
    CHECK(res.counts.hits == 0);
}

TEST_CASE("run_reference takes depth_bits from the stream header", "[ref][quant]") {
    StreamHeader h;
    h.depth_bits = 16;
    MemorySource src(h);
    src.add_frame(0);
    src.add_tile(make_tile(0, 0, 0, {frag(0, 0, 0x1000, A, 'F'), frag(0, 0, 0x2000, B, 'F'),
                                     frag(0, 0, 0x3456, A, 'B')}));
    RefConfig cfg;   // depth_bits 24 here, but the stream says 16: 0x3456 widened to 0x345600
    const auto res = run_reference(cfg, src);
    REQUIRE(res.frames.size() == 1);
    CHECK(text(res.frames[0].records) == "hit 0 0 1 2 3429888\n");
}

TEST_CASE("ids at the id_bits limit", "[ref][ids]") {
    RefConfig cfg;   // id_bits 7: ids 0 and 127 are legal
    auto r = run_tile(cfg, {frag(0, 0, 10, 127, 'F'), frag(0, 0, 20, 0, 'F'), frag(0, 0, 30, 127, 'B')});
    CHECK(r.out == "hit 0 0 0 127 30\n");
    cfg.id_bits = 16;
    r = run_tile(cfg, {frag(0, 0, 10, 65535, 'F'), frag(0, 0, 20, 65534, 'F'), frag(0, 0, 30, 65535, 'B')});
    CHECK(r.out == "hit 0 0 65534 65535 30\n");
}

TEST_CASE("broken preconditions are input errors and leave nothing behind", "[ref][errors]") {
    RefConfig cfg;
    std::vector<RefRecord> out;
    RefCounts counts;
    Tile t = make_tile(0, 1, 0, {frag(16, 0, 10, A, 'F'), frag(15, 0, 10, A, 'F')});   // x 15 is in tile 0
    CHECK_THROWS_AS(reference_tile(cfg, t, out, counts), InputError);
    t = make_tile(0, 0, 0, {frag(0, 0, 10, 128, 'F')});   // id 128 needs 8 bits
    CHECK_THROWS_AS(reference_tile(cfg, t, out, counts), InputError);
    t = make_tile(0, 0, 0, {frag(0, 0, 1u << 24, A, 'F')});   // depth needs 25 bits
    CHECK_THROWS_AS(reference_tile(cfg, t, out, counts), InputError);
    CHECK(out.empty());
    CHECK(counts.tiles == 0);
    CHECK(counts.fragments == 0);

    StreamHeader h;
    h.tile_w = 8;
    MemorySource mismatch(h);
    CHECK_THROWS_AS(run_reference(cfg, mismatch), InputError);
    MemorySource no_frame(StreamHeader{});
    no_frame.add_tile(make_tile(0, 0, 0, {}));
    CHECK_THROWS_AS(run_reference(cfg, no_frame), InputError);
}

TEST_CASE("ref_config_from copies the contract's keys", "[ref][config]") {
    SimConfig sim;
    sim.tile.width = 8;
    sim.tile.height = 4;
    sim.zeb.list_length = 3;
    sim.zeb.z_bits = 12;
    sim.zeb.id_bits = 9;
    sim.zeb.tie = TiePolicy::Arrival;
    sim.tester.stack_depth = 5;
    sim.tester.output = OutputMode::Tile;
    const RefConfig c = ref_config_from(sim, 20);
    CHECK(c.tile_w == 8);
    CHECK(c.tile_h == 4);
    CHECK(c.list_length == 3);
    CHECK(c.z_bits == 12);
    CHECK(c.id_bits == 9);
    CHECK(c.tie == TiePolicy::Arrival);
    CHECK(c.stack_depth == 5);
    CHECK(c.output == OutputMode::Tile);
    CHECK(c.depth_bits == 20);
}
