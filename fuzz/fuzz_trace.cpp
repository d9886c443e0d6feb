// The trace reader, plain and gzip. The first byte picks the read chunk (1..63
// bytes, so refills fall everywhere, or with 63 in its low six bits the
// default 1 MiB, so that the whole-line parse runs), the object id width
// (bit 6) and whether the rest is gzip-compressed before reading (bit 7); the
// rest is the trace. Each input is read twice, with the AVX-512 whole-line
// parse (where the CPU has it) and with the portable one, and both must give
// the same events, fragments and error, and take the same lines whole.
#include <zlib.h>

#include <memory>
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

// Everything a read gives, as bytes: the events, each tile's fragments, and
// the error that ended it.
std::string read_all(const std::string& path, const rbcd::TraceLimits& lim) {
    std::string got;
    std::unique_ptr<rbcd::TraceReader> reader;
    try {
        reader = std::make_unique<rbcd::TraceReader>(path, lim);
        rbcd::TraceReader& r = *reader;
        rbcd::Tile t;
        for (;;) {
            const auto ev = r.next(t);
            got += static_cast<char>('0' + static_cast<int>(ev));
            if (ev == rbcd::FragmentSource::Event::End) break;
            if (ev == rbcd::FragmentSource::Event::Tile) {
                if (t.frags.size() > lim.max_tile_fragments) rbcd::fuzz::finding("tile above max_tile_fragments");
                for (const auto& fr : t.frags) {
                    if (fr.x >= r.header().screen_w || fr.y >= r.header().screen_h)
                        rbcd::fuzz::finding("fragment outside the screen accepted");
                    const std::uint32_t v[5] = {fr.x, fr.y, fr.depth, fr.id,
                                                static_cast<std::uint32_t>(fr.facing) * 2 + fr.culled};
                    got.append(reinterpret_cast<const char*>(v), sizeof v);
                }
            }
        }
        if (r.next(t) != rbcd::FragmentSource::Event::End) rbcd::fuzz::finding("End is not sticky");
    } catch (const rbcd::InputError& e) {
        const std::string m = e.what();
        if (m.find('\n') != std::string::npos) rbcd::fuzz::finding("multi-line message: " + m);
        got += "error " + m;
    }
    // The lines the whole-line parse took: the same for both, or one parse
    // would leave lines to the slow path that the other takes.
    if (reader) got += " whole " + std::to_string(reader->lines_taken_whole());
    return got;
}
} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const unsigned mode = data[0];
    ++data;
    --size;
    rbcd::TraceLimits lim;
    lim.read_chunk = (mode & 63) == 63 ? std::size_t(1) << 20 : 1 + (mode & 63);
    lim.max_line_bytes = 4096;
    lim.max_tile_fragments = 4096;
    lim.max_work_cycles = std::uint64_t(1) << 50;
    lim.cycles_per_fragment = 8;
    lim.id_bits = 1 + (mode >> 6 & 1) * 15;
    const std::string bytes = (mode & 128) ? gzip(data, size) : std::string(reinterpret_cast<const char*>(data), size);
    rbcd::fuzz::MemFile f(bytes.data(), bytes.size());
    const std::string wide = read_all(f.path(), lim);
    lim.wide_parse = false;
    if (read_all(f.path(), lim) != wide) rbcd::fuzz::finding("the AVX-512 and portable parses read differently");
    return 0;
}
