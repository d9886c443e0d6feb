#include "rbcd/run/part_digest.h"

#include <fcntl.h>
#include <unistd.h>
#define XXH_STATIC_LINKING_ONLY
#include <xxhash.h>
#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "rbcd/common/errors.h"
#include "rbcd/common/write_all.h"
#include "rbcd/run/provenance.h"

namespace rbcd {

namespace xxh3_blocks {

namespace {

constexpr std::size_t kStripe = 64;
constexpr std::size_t kStripesPerBlock = kBlockBytes / kStripe;   // 16: the default secret's
constexpr std::size_t kSecretBytes = 192;
constexpr std::uint64_t kPrime32_1 = 0x9E3779B1u;
constexpr std::uint64_t kPrime64_1 = 0x9E3779B185EBCA87ull;
constexpr std::uint64_t kPrime64_2 = 0xC2B2AE3D27D4EB4Full;
// Where XXH3 reads its secret for each use (xxhash.h names them).
constexpr std::size_t kScrambleKey = kSecretBytes - kStripe;        // 128
constexpr std::size_t kLastStripeKey = kSecretBytes - kStripe - 7;  // XXH_SECRET_LASTACC_START
constexpr std::size_t kMergeLow = 11;                               // XXH_SECRET_MERGEACCS_START
constexpr std::size_t kMergeHigh = kSecretBytes - 64 - 11;

// The default secret and the starting accumulators, from libxxhash itself (a
// reset state holds both): the digest cannot drift from the library's by a
// constant copied wrong.
struct Defaults {
    Lanes acc;
    unsigned char secret[kSecretBytes];
};
const Defaults& defaults() {
    static const Defaults d = [] {
        Defaults r{};
        XXH3_state_t s;
        XXH3_INITSTATE(&s);
        XXH3_128bits_reset(&s);
        if (!s.extSecret || s.secretLimit + kStripe != kSecretBytes || s.nbStripesPerBlock != kStripesPerBlock)
            throw std::logic_error("libxxhash: unexpected XXH3 state layout");
        std::memcpy(r.acc.v, s.acc, sizeof r.acc.v);
        std::memcpy(r.secret, s.extSecret, kSecretBytes);
        return r;
    }();
    return d;
}

std::uint64_t load64(const unsigned char* p) {
    std::uint64_t v;
    std::memcpy(&v, p, 8);
    return v;   // x86 and the other little-endian hosts Debian builds for
}

void stripe_portable(std::uint64_t* acc, const unsigned char* p, const unsigned char* key) {
    for (std::size_t i = 0; i < 8; ++i) {
        const std::uint64_t d = load64(p + 8 * i);
        const std::uint64_t dk = d ^ load64(key + 8 * i);
        acc[i ^ 1] += d;
        acc[i] += (dk & 0xFFFFFFFFu) * (dk >> 32);
    }
}

void scramble_portable(std::uint64_t* acc, const unsigned char* secret) {
    for (std::size_t i = 0; i < 8; ++i) {
        std::uint64_t a = acc[i];
        a ^= a >> 47;
        a ^= load64(secret + kScrambleKey + 8 * i);
        acc[i] = a * kPrime32_1;
    }
}

void blocks_portable(const unsigned char* p, std::size_t n, Lanes* acc, Lanes* sums) {
    const unsigned char* secret = defaults().secret;
    for (std::size_t b = 0; b < n; ++b, p += kBlockBytes) {
        Lanes s{};
        Lanes& x = acc ? *acc : s;
        for (std::size_t j = 0; j < kStripesPerBlock; ++j) stripe_portable(x.v, p + j * kStripe, secret + 8 * j);
        if (acc) scramble_portable(acc->v, secret);
        else sums[b] = s;
    }
}

#if defined(__x86_64__)
// One body for the three widths: W 64-bit words a register, 8 / W registers
// a stripe. The keyed product is one unsigned 32 x 32 multiply of each word's
// halves; the words are added to the neighbouring lane (i ^ 1), a swap of the
// 32-bit pairs within each 128 bits.
#define RBCD_XXH3_BLOCKS(NAME, TARGET, VEC, R, LOAD, STORE, ZERO, XOR, ADD, MUL, SRLI, SLLI, SWAP, SET1)          \
    __attribute__((target(TARGET))) void NAME(const unsigned char* p, std::size_t n, Lanes* acc, Lanes* sums) {  \
        const unsigned char* secret = defaults().secret;                                                          \
        VEC key[kStripesPerBlock][R];                                                                              \
        for (std::size_t j = 0; j < kStripesPerBlock; ++j)                                                         \
            for (std::size_t r = 0; r < R; ++r) key[j][r] = LOAD(secret + 8 * j + r * sizeof(VEC));               \
        VEC skey[R], a[R];                                                                                         \
        for (std::size_t r = 0; r < R; ++r) {                                                                      \
            skey[r] = LOAD(secret + kScrambleKey + r * sizeof(VEC));                                               \
            a[r] = acc ? LOAD(reinterpret_cast<const unsigned char*>(acc->v) + r * sizeof(VEC)) : ZERO();         \
        }                                                                                                          \
        const VEC prime = SET1(static_cast<long long>(kPrime32_1));                                                \
        for (std::size_t b = 0; b < n; ++b, p += kBlockBytes) {                                                   \
            VEC x[R];                                                                                              \
            for (std::size_t r = 0; r < R; ++r) x[r] = acc ? a[r] : ZERO();                                        \
            for (std::size_t j = 0; j < kStripesPerBlock; ++j)                                                     \
                for (std::size_t r = 0; r < R; ++r) {                                                              \
                    const VEC d = LOAD(p + j * kStripe + r * sizeof(VEC));                                         \
                    const VEC dk = XOR(d, key[j][r]);                                                              \
                    x[r] = ADD(x[r], SWAP(d));                                                                     \
                    x[r] = ADD(x[r], MUL(dk, SRLI(dk, 32)));                                                       \
                }                                                                                                  \
            if (acc) {                                                                                             \
                for (std::size_t r = 0; r < R; ++r) {                                                              \
                    VEC y = XOR(XOR(x[r], SRLI(x[r], 47)), skey[r]);                                               \
                    a[r] = ADD(MUL(y, prime), SLLI(MUL(SRLI(y, 32), prime), 32));                                  \
                }                                                                                                  \
            } else {                                                                                               \
                for (std::size_t r = 0; r < R; ++r)                                                                \
                    STORE(reinterpret_cast<unsigned char*>(sums[b].v) + r * sizeof(VEC), x[r]);                   \
            }                                                                                                      \
        }                                                                                                          \
        if (acc)                                                                                                   \
            for (std::size_t r = 0; r < R; ++r) STORE(reinterpret_cast<unsigned char*>(acc->v) + r * sizeof(VEC), a[r]); \
    }

#define RBCD_LD128(p) _mm_loadu_si128(reinterpret_cast<const __m128i*>(p))
#define RBCD_ST128(p, v) _mm_storeu_si128(reinterpret_cast<__m128i*>(p), v)
#define RBCD_SWAP128(v) _mm_shuffle_epi32(v, 0x4E)
RBCD_XXH3_BLOCKS(blocks_sse2, "sse2", __m128i, 4, RBCD_LD128, RBCD_ST128, _mm_setzero_si128, _mm_xor_si128,
                 _mm_add_epi64, _mm_mul_epu32, _mm_srli_epi64, _mm_slli_epi64, RBCD_SWAP128, _mm_set1_epi64x)

#define RBCD_LD256(p) _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p))
#define RBCD_ST256(p, v) _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v)
#define RBCD_SWAP256(v) _mm256_shuffle_epi32(v, 0x4E)
RBCD_XXH3_BLOCKS(blocks_avx2, "avx2", __m256i, 2, RBCD_LD256, RBCD_ST256, _mm256_setzero_si256, _mm256_xor_si256,
                 _mm256_add_epi64, _mm256_mul_epu32, _mm256_srli_epi64, _mm256_slli_epi64, RBCD_SWAP256,
                 _mm256_set1_epi64x)

// (GCC 12's unmasked AVX-512 intrinsics pass an undefined vector as their
// unused source, which -Wmaybe-uninitialized reports at every use.)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#define RBCD_LD512(p) _mm512_loadu_si512(p)
#define RBCD_ST512(p, v) _mm512_storeu_si512(p, v)
#define RBCD_SWAP512(v) _mm512_shuffle_epi32(v, _MM_PERM_BADC)
RBCD_XXH3_BLOCKS(blocks_avx512, "avx512f", __m512i, 1, RBCD_LD512, RBCD_ST512, _mm512_setzero_si512,
                 _mm512_xor_si512, _mm512_add_epi64, _mm512_mul_epu32, _mm512_srli_epi64, _mm512_slli_epi64,
                 RBCD_SWAP512, _mm512_set1_epi64)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
#endif

} // namespace

bool available(Isa isa) {
#if defined(__x86_64__)
    __builtin_cpu_init();
    switch (isa) {
    case Isa::portable:
    case Isa::sse2: return true;
    case Isa::avx2: return __builtin_cpu_supports("avx2");
    case Isa::avx512: return __builtin_cpu_supports("avx512f");
    }
    return false;
#else
    return isa == Isa::portable;
#endif
}

Isa best_isa() {
    static const Isa best = [] {
        for (Isa i : {Isa::avx512, Isa::avx2, Isa::sse2})
            if (available(i)) return i;
        return Isa::portable;
    }();
    return best;
}

const char* isa_name(Isa isa) {
    switch (isa) {
    case Isa::portable: return "portable";
    case Isa::sse2: return "sse2";
    case Isa::avx2: return "avx2";
    case Isa::avx512: return "avx512";
    }
    return "?";
}

Lanes start() { return defaults().acc; }

void blocks(Isa isa, const unsigned char* p, std::size_t n, Lanes* acc, Lanes* sums) {
    if (n == 0) return;
    defaults();   // constructed before a vector loop reads it
    switch (available(isa) ? isa : Isa::portable) {
#if defined(__x86_64__)
    case Isa::avx512: blocks_avx512(p, n, acc, sums); return;
    case Isa::avx2: blocks_avx2(p, n, acc, sums); return;
    case Isa::sse2: blocks_sse2(p, n, acc, sums); return;
#endif
    default: blocks_portable(p, n, acc, sums); return;
    }
}

void chain(Lanes& acc, const Lanes* sums, std::size_t n) {
    const unsigned char* secret = defaults().secret;
    for (std::size_t b = 0; b < n; ++b) {
        for (std::size_t i = 0; i < 8; ++i) acc.v[i] += sums[b].v[i];
        scramble_portable(acc.v, secret);
    }
}

std::uint64_t chained_blocks(std::uint64_t len) { return len ? (len - 1) / kBlockBytes : 0; }

std::uint64_t tail_start(std::uint64_t len) {
    return std::min(chained_blocks(len) * kBlockBytes, len >= kStripe ? len - kStripe : 0);
}

namespace {
std::uint64_t fold_mul(std::uint64_t a, std::uint64_t b) {
    const unsigned __int128 p = static_cast<unsigned __int128>(a) * b;
    return static_cast<std::uint64_t>(p) ^ static_cast<std::uint64_t>(p >> 64);
}
std::uint64_t merge(const Lanes& acc, const unsigned char* key, std::uint64_t h) {
    for (std::size_t i = 0; i < 4; ++i)
        h += fold_mul(acc.v[2 * i] ^ load64(key + 16 * i), acc.v[2 * i + 1] ^ load64(key + 16 * i + 8));
    h ^= h >> 37;
    h *= 0x165667919E3779F9ull;
    return h ^ (h >> 32);
}
} // namespace

Digest128 finish(Lanes acc, const unsigned char* tail, std::uint64_t len) {
    const unsigned char* secret = defaults().secret;
    const std::uint64_t last_block = chained_blocks(len) * kBlockBytes;
    const unsigned char* block = tail + (last_block - tail_start(len));
    // The last block's whole stripes but its last byte's, then the input's
    // last 64 bytes with a key of their own.
    const std::size_t stripes = static_cast<std::size_t>((len - 1 - last_block) / kStripe);
    for (std::size_t j = 0; j < stripes; ++j) stripe_portable(acc.v, block + j * kStripe, secret + 8 * j);
    stripe_portable(acc.v, tail + (len - kStripe - tail_start(len)), secret + kLastStripeKey);
    Digest128 d;
    d.low = merge(acc, secret + kMergeLow, len * kPrime64_1);
    d.high = merge(acc, secret + kMergeHigh, ~(len * kPrime64_2));
    return d;
}

} // namespace xxh3_blocks

using namespace xxh3_blocks;

namespace {

constexpr std::size_t kSumsBuffered = 1024;   // 64 KiB of sums a write

std::string hex64(std::uint64_t v) {
    char b[17];
    std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(v));
    return b;
}

bool parse_hex64(const std::string& s, std::uint64_t& v) {
    if (s.size() != 16 || s.find_first_not_of("0123456789abcdef") != std::string::npos) return false;
    v = std::stoull(s, nullptr, 16);
    return true;
}

// `n` bytes at `off` into `dst`; false on an error or the file's end.
bool pread_all(int fd, unsigned char* dst, std::size_t n, std::uint64_t off) {
    while (n > 0) {
        const ssize_t got = ::pread(fd, dst, n, static_cast<off_t>(off));
        if (got < 0 && errno == EINTR) continue;
        if (got <= 0) return false;
        dst += got;
        n -= static_cast<std::size_t>(got);
        off += static_cast<std::uint64_t>(got);
    }
    return true;
}

} // namespace

PartDigest::PartDigest(std::uint64_t from, std::uint64_t to, std::string sums_path)
    : from_(from), to_(std::max(from, to)), next_(from), stage_(new unsigned char[kBlockBytes]),
      acc_(start()), sums_path_(std::move(sums_path)) {
    if (from % kBlockBytes || to % kBlockBytes)
        throw std::invalid_argument("PartDigest: the part's bounds must be whole blocks");
    if (from_ > 0) {
        sums_.reserve(kSumsBuffered);
        sums_fd_ = ::open(sums_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
        if (sums_fd_ < 0) stopped_ = true;
    }
}

PartDigest::~PartDigest() {
    if (sums_fd_ >= 0) ::close(sums_fd_);
}

void PartDigest::file(int fd) {
    fd_ = fd;
    id_ = file_id(fd);
    pos_ = 0;
}

void PartDigest::raw(const void* bytes, std::size_t n) {
    take(static_cast<const unsigned char*>(bytes), pos_, n);
    pos_ += n;
}

void PartDigest::fill_in(std::uint64_t upto) {
    unsigned char buf[16 * kBlockBytes];
    while (!stopped_ && next_ < upto) {
        const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(sizeof buf, upto - next_));
        if (fd_ < 0 || !pread_all(fd_, buf, n, next_)) stopped_ = true;
        else take(buf, next_, n);
    }
}

void PartDigest::take(const unsigned char* p, std::uint64_t at, std::size_t n) {
    if (stopped_ || next_ >= to_ || at + n <= next_) return;
    if (at > next_) {
        // Bytes the reader passed over (before its first frame): read here.
        fill_in(std::min(at, to_));
        if (stopped_ || next_ >= to_) return;
    }
    const std::size_t skip = static_cast<std::size_t>(next_ - at);
    p += skip;
    n = static_cast<std::size_t>(std::min<std::uint64_t>(n - skip, to_ - next_));
    next_ += n;
    if (staged_) {
        const std::size_t k = std::min<std::size_t>(n, kBlockBytes - staged_);
        std::memcpy(stage_.get() + staged_, p, k);
        staged_ += k;
        p += k;
        n -= k;
        if (staged_ < kBlockBytes) return;
        staged_ = 0;
        const unsigned char* s = stage_.get();
        if (from_ == 0) blocks(best_isa(), s, 1, &acc_, nullptr);
        else {
            if (sums_.size() >= kSumsBuffered && !flush_sums()) return;
            sums_.emplace_back();
            blocks(best_isa(), s, 1, nullptr, &sums_.back());
        }
        ++done_;
    }
    std::size_t whole = n / kBlockBytes;
    if (from_ == 0) {
        blocks(best_isa(), p, whole, &acc_, nullptr);
        done_ += whole;
        p += whole * kBlockBytes;
    } else {
        while (whole > 0) {
            if (sums_.size() >= kSumsBuffered && !flush_sums()) return;
            const std::size_t k = std::min(whole, kSumsBuffered - sums_.size());
            const std::size_t at_sum = sums_.size();
            sums_.resize(at_sum + k);
            blocks(best_isa(), p, k, nullptr, sums_.data() + at_sum);
            done_ += k;
            whole -= k;
            p += k * kBlockBytes;
        }
    }
    staged_ = n % kBlockBytes;
    std::memcpy(stage_.get(), p, staged_);
}

bool PartDigest::flush_sums() {
    const bool ok = write_all(sums_fd_, sums_.data(), sums_.size() * sizeof(Lanes)) == 0;
    if (ok) written_ += sums_.size();
    sums_.clear();
    if (!ok) {
        // Not the run's failure: the parent hashes the rest from the file.
        stopped_ = true;
        ::close(std::exchange(sums_fd_, -1));
    }
    return ok;
}

nlohmann::json PartDigest::finish() {
    nlohmann::json j;
    j["from"] = from_;
    if (from_ == 0) {
        j["blocks"] = done_;
        nlohmann::json acc = nlohmann::json::array();
        for (std::uint64_t w : acc_.v) acc.push_back(hex64(w));
        j["acc"] = acc;
    } else {
        if (sums_fd_ >= 0) flush_sums();   // the sums before a read that failed are good
        // A close that fails may have lost what was written before it.
        if (sums_fd_ >= 0 && ::close(std::exchange(sums_fd_, -1)) != 0) written_ = 0;
        j["blocks"] = written_;
    }
    if (id_)
        j["file"] = {{"dev", id_->dev}, {"ino", id_->ino}, {"size", id_->size}, {"mtime_ns", id_->mtime_ns}};
    return j;
}

void SplitDigest::add(const nlohmann::json& j, const std::string& sums_path) {
    const auto bad = [] { return RunError("--jobs: a worker's digest is malformed"); };
    const auto u64 = [&](const nlohmann::json& o, const char* key) {
        const auto& v = o.at(key);
        if (!v.is_number_integer() || (!v.is_number_unsigned() && v.get<std::int64_t>() < 0)) throw bad();
        return v.get<std::uint64_t>();
    };
    try {
        Part p;
        p.from = u64(j, "from");
        p.blocks = u64(j, "blocks");
        if (p.from % kBlockBytes || p.blocks > (UINT64_MAX - p.from) / kBlockBytes) throw bad();
        if (j.contains("acc")) {
            const auto& a = j.at("acc");
            if (p.from != 0 || !a.is_array() || a.size() != 8) throw bad();
            for (std::size_t i = 0; i < 8; ++i)
                if (!a[i].is_string() || !parse_hex64(a[i].get<std::string>(), p.acc.v[i])) throw bad();
            p.chained = true;
        } else {
            if (p.from == 0) throw bad();
            p.sums_path = sums_path;
        }
        if (j.contains("file")) {
            const auto& f = j.at("file");
            FileId id;
            id.dev = u64(f, "dev");
            id.ino = u64(f, "ino");
            id.size = u64(f, "size");
            if (!f.at("mtime_ns").is_number_integer()) throw bad();
            id.mtime_ns = f.at("mtime_ns").get<std::int64_t>();
            p.file = id;
        } else if (p.blocks > 0) {
            throw bad();   // blocks of an unknown file
        }
        parts.push_back(std::move(p));
    } catch (const nlohmann::json::exception&) {
        throw bad();
    }
}

namespace {

// The file's blocks [from, to) chained into acc, read here; false on a read error.
bool chain_from_file(int fd, std::uint64_t from, std::uint64_t to, Lanes& acc) {
    constexpr std::size_t kRead = 1024 * kBlockBytes;
    std::unique_ptr<unsigned char[]> buf;
    while (from < to) {
        if (!buf) buf.reset(new unsigned char[kRead]);
        const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(kRead, to - from));
        if (!pread_all(fd, buf.get(), n, from)) return false;
        blocks(best_isa(), buf.get(), n / kBlockBytes, &acc, nullptr);
        from += n;
    }
    return true;
}

// A worker's sums [skip, skip + n) chained into acc, as many as its file
// holds: how many were.
std::uint64_t chain_sums(const std::string& path, std::uint64_t skip, std::uint64_t n, Lanes& acc) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return 0;
    std::vector<Lanes> buf(kSumsBuffered);
    std::uint64_t done = 0;
    while (done < n) {
        const std::size_t k = static_cast<std::size_t>(std::min<std::uint64_t>(n - done, buf.size()));
        if (!pread_all(fd, reinterpret_cast<unsigned char*>(buf.data()), k * sizeof(Lanes), (skip + done) * sizeof(Lanes)))
            break;
        chain(acc, buf.data(), k);
        done += k;
    }
    ::close(fd);
    return done;
}

std::string digest_hex(const Digest128& d) { return hex64(d.high) + hex64(d.low); }

} // namespace

FileDigest digest_from_parts(const std::string& path, const SplitDigest& split) {
    FileDigest out;
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        out.note = std::string("cannot read: ") + std::strerror(errno);
        return out;
    }
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    const std::optional<FileId> now = file_id(fd);
    bool same = now && *now == split.planned;
    for (const auto& p : split.parts) same = same && (!p.file || *p.file == split.planned);
    const auto changed = [&] {
        out.note = "the file was replaced or rewritten during the run";
        return out;
    };
    if (!same) return changed();
    // Rewritten in place while it is read here: neither file's digest.
    const auto unchanged_since = [&] {
        const std::optional<FileId> after = file_id(fd);
        return after && *after == split.planned;
    };
    const std::uint64_t len = now->size;
    out.size = len;
    if (len <= 240) {
        // Not the block hash: XXH3's short inputs have algorithms of their own.
        unsigned char buf[240];
        if (!pread_all(fd, buf, static_cast<std::size_t>(len), 0)) {
            out.note = "read error";
            return out;
        }
        if (!unchanged_since()) return changed();
        out.hex = xxh128_hex(buf, static_cast<std::size_t>(len));
        return out;
    }
    const std::uint64_t end = chained_blocks(len) * kBlockBytes;
    Lanes acc = start();
    std::uint64_t at = 0;   // the bytes chained so far
    bool ok = true;
    for (const auto& p : split.parts) {
        if (!ok || at >= end) break;
        // What no worker hashed before this part, from the file.
        if (p.from > at) {
            ok = chain_from_file(fd, at, std::min(p.from, end), acc);
            at = std::min(p.from, end);
        }
        const std::uint64_t part_end = std::min(p.from + p.blocks * kBlockBytes, end);
        if (!ok || part_end <= at) continue;
        if (p.chained) {
            // Only as the file's first part, whole: accumulators past the
            // last block's start, or over blocks already chained, are no use.
            if (at != 0 || p.from + p.blocks * kBlockBytes > end) continue;
            acc = p.acc;
            at = part_end;
        } else {
            at += kBlockBytes * chain_sums(p.sums_path, (at - p.from) / kBlockBytes, (part_end - at) / kBlockBytes, acc);
            // Fewer sums than the part said: those blocks from the file.
            ok = chain_from_file(fd, at, part_end, acc);
            at = part_end;
        }
    }
    if (ok) ok = chain_from_file(fd, at, end, acc);
    std::vector<unsigned char> tail(static_cast<std::size_t>(len - tail_start(len)));
    if (ok) ok = pread_all(fd, tail.data(), tail.size(), tail_start(len));
    if (!ok) {
        out.note = "read error";
        return out;
    }
    if (!unchanged_since()) return changed();
    out.hex = digest_hex(finish(acc, tail.data(), len));
    return out;
}

} // namespace rbcd
