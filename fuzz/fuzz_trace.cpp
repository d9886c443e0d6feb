// The trace reader, plain and gzip. The first byte picks the read chunk (1..64
// bytes, so refills fall everywhere) and whether the rest is gzip-compressed
// before reading (bit 7); the rest is the trace.
#include <zlib.h>

#include <string>

#include "rbcd/common/errors.h"
#include "rbcd/fuzz/fuzz_util.h"
#include "rbcd/io/trace_reader.h"

namespace {
std::string gzip(const std::uint8_t* data, std::size_t size) {
    z_stream zs{};
    if (deflateInit2(&zs, 1, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) std::abort();
    std::string out(deflateBound(&zs, size) + 32, '\0');
    zs.next_in = const_cast<Bytef*>(data);
    zs.avail_in = static_cast<uInt>(size);
    zs.next_out = reinterpret_cast<Bytef*>(out.data());
    zs.avail_out = static_cast<uInt>(out.size());
    if (deflate(&zs, Z_FINISH) != Z_STREAM_END) std::abort();
    out.resize(zs.total_out);
    deflateEnd(&zs);
    return out;
}
} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const unsigned mode = data[0];
    ++data;
    --size;
    rbcd::TraceLimits lim;
    lim.read_chunk = 1 + (mode & 63);
    lim.max_line_bytes = 4096;
    lim.max_tile_fragments = 4096;
    lim.max_work_cycles = std::uint64_t(1) << 50;
    lim.cycles_per_fragment = 8;
    lim.id_bits = 1 + (mode >> 6 & 1) * 15;
    const std::string bytes = (mode & 128) ? gzip(data, size) : std::string(reinterpret_cast<const char*>(data), size);
    rbcd::fuzz::MemFile f(bytes.data(), bytes.size());
    try {
        rbcd::TraceReader r(f.path(), lim);
        rbcd::Tile t;
        std::uint64_t frags = 0;
        for (;;) {
            const auto ev = r.next(t);
            if (ev == rbcd::FragmentSource::Event::End) break;
            if (ev == rbcd::FragmentSource::Event::Tile) {
                frags += t.frags.size();
                if (t.frags.size() > lim.max_tile_fragments) rbcd::fuzz::finding("tile above max_tile_fragments");
                for (const auto& fr : t.frags)
                    if (fr.x >= r.header().screen_w || fr.y >= r.header().screen_h)
                        rbcd::fuzz::finding("fragment outside the screen accepted");
            }
        }
        if (r.next(t) != rbcd::FragmentSource::Event::End) rbcd::fuzz::finding("End is not sticky");
    } catch (const rbcd::InputError& e) {
        const std::string m = e.what();
        if (m.find('\n') != std::string::npos) rbcd::fuzz::finding("multi-line message: " + m);
    }
    return 0;
}
