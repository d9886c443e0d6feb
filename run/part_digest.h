// A trace's XXH3-128 digest (docs/provenance.md) taken in parts by the
// workers of rbcd-sim --jobs, each over the bytes it reads anyway, instead of
// by the parent reading the whole file again after them (or beside the last
// of them, on a core it would otherwise have had).
//
// XXH3 hashes an input of more than 240 bytes in blocks of 1,024. Within a
// block its eight 64-bit accumulators only add: each 64-byte stripe adds its
// words and the products of their keyed 32-bit halves. A scramble (xorshift,
// xor, multiply) ends the block. So the sum of a block can be taken by
// whoever holds its bytes before the accumulators it adds to are known, and
// the chain (add a block's sum, scramble: a few instructions a block) run in
// order afterwards by whoever has them all:
//
//     worker 0:  blocks [0, B1) chained from XXH3's start  -> 8 accumulators
//     worker k:  blocks [Bk, Bk+1), each block's sum        -> a file of 64-byte sums
//     parent:    the accumulators through every part's sums, whatever no
//                worker hashed read from the file, then the last block, the
//                last stripe and the merge into 128 bits
//
// The digest is XXH3-128's, bit for bit, as `xxhsum -H2` prints it; tests
// hold it to libxxhash's for every kind of length and cut.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rbcd/io/gzip_stream.h"
#include "rbcd/run/provenance.h"   // FileId

namespace rbcd {

namespace xxh3_blocks {

constexpr std::uint64_t kBlockBytes = 1024;

struct Lanes {
    std::uint64_t v[8];
};

struct Digest128 {
    std::uint64_t low = 0, high = 0;
};

// The vector units a block's sum is taken with; every one gives the same sums.
enum class Isa { portable, sse2, avx2, avx512 };
bool available(Isa isa);
Isa best_isa();   // the widest available, decided once
const char* isa_name(Isa isa);

// The accumulators before the first block (libxxhash's, after its reset).
Lanes start();
// `n` whole blocks at `p`: chained into `*acc` (sums null), or each block's
// sum into sums[0, n) (acc null).
void blocks(Isa isa, const unsigned char* p, std::size_t n, Lanes* acc, Lanes* sums);
// acc: a block's sum added, then scrambled, for `n` sums.
void chain(Lanes& acc, const Lanes* sums, std::size_t n);

// The blocks a `len`-byte input chains before its last, partial or whole, one
// ((len - 1) / 1024 of them; the last is not scrambled), and where the bytes
// finish() needs start: the last block's, or its last 64 when it is shorter.
std::uint64_t chained_blocks(std::uint64_t len);
std::uint64_t tail_start(std::uint64_t len);
// The digest of a `len`-byte input (len > 240) from the accumulators after its
// chained blocks and its bytes from tail_start(len) to its end.
Digest128 finish(Lanes acc, const unsigned char* tail, std::uint64_t len);

} // namespace xxh3_blocks

// A worker's part of the digest, given to its trace reader: the blocks of
// bytes [from, to) (multiples of 1,024) out of the bytes the reader reads.
// Those it skipped over (the few before its first frame) are read with
// pread(2). From 0: chained; otherwise each block's sum goes to `sums_path`,
// 64 bytes a block, little-endian words. Memory: a block and a buffer of sums.
// A part that cannot be had (the file ends early, a read fails, its sums
// cannot be written) stops where it is: the parent hashes what is missing
// from the file. The run does not fail for it.
class PartDigest final : public RawObserver {
public:
    PartDigest(std::uint64_t from, std::uint64_t to, std::string sums_path);
    ~PartDigest() override;
    PartDigest(const PartDigest&) = delete;
    PartDigest& operator=(const PartDigest&) = delete;
    void file(int fd) override;
    void raw(const void* bytes, std::size_t n) override;
    void end() override {}
    void gap(std::uint64_t resume_at) override { pos_ = resume_at; }
    // {"from", "blocks" (hashed, and for a later part written), "acc" (the
    // first part's: eight words in hex), "file" {"dev", "ino", "size",
    // "mtime_ns"}}, for the worker's stats; the sums written out.
    nlohmann::json finish();

private:
    void take(const unsigned char* p, std::uint64_t at, std::size_t n);
    void fill_in(std::uint64_t upto);   // pread of [next_, upto)
    bool flush_sums();   // false: they could not be written, and the part stops

    std::uint64_t from_, to_;
    std::uint64_t pos_ = 0;    // the file offset of the next byte the reader shows
    std::uint64_t next_;       // the next byte the digest needs (staged ones counted)
    bool stopped_ = false;
    int fd_ = -1;
    std::optional<FileId> id_;
    std::unique_ptr<unsigned char[]> stage_;
    std::size_t staged_ = 0;
    std::uint64_t done_ = 0;      // blocks hashed
    std::uint64_t written_ = 0;   // a later part's: sums written
    xxh3_blocks::Lanes acc_{};
    std::vector<xxh3_blocks::Lanes> sums_;   // not yet written
    std::string sums_path_;
    int sums_fd_ = -1;
};

// What the parent knows of the parts, in file order.
struct SplitDigest {
    struct Part {
        std::uint64_t from = 0, blocks = 0;
        bool chained = false;          // from 0, `acc` after its blocks
        xxh3_blocks::Lanes acc{};
        std::string sums_path;         // else: `blocks` sums
        std::optional<FileId> file;    // what the worker read
    };
    FileId planned;                    // the trace when the parts were cut
    std::vector<Part> parts;
    // Part k's entry from its worker's "digest" object (PartDigest::finish);
    // throws RunError when it is malformed.
    void add(const nlohmann::json& j, const std::string& sums_path);
};

// The digest of the file at `path` from its parts: the size and the 32 hex
// digits xxhsum -H2 prints, or an empty digest and a note (the file was
// replaced or rewritten since it was cut, or cannot be read).
struct FileDigest {
    std::uint64_t size = 0;
    std::string hex, note;
};
FileDigest digest_from_parts(const std::string& path, const SplitDigest& split);

} // namespace rbcd
