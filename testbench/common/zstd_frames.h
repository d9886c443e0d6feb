// zstd traces made piece by piece for the tests (link RBCD::zstd): each
// piece one zstd frame, stating its size as TraceWriter's do, or streamed
// without it; and a text cut before each of its frame records.
#pragma once
#include <zstd.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace rbcd::test {

inline std::string zstd_frames(const std::vector<std::string>& pieces, bool sized = true) {
    std::string out;
    for (const std::string& p : pieces) {
        std::string z(ZSTD_compressBound(p.size()) + 32, '\0');
        std::size_t n;
        if (sized) {
            n = ZSTD_compress(z.data(), z.size(), p.data(), p.size(), 1);
        } else {
            // Half given first: the size is not known when the header is written.
            ZSTD_CCtx* c = ZSTD_createCCtx();
            ZSTD_inBuffer in{p.data(), p.size() / 2, 0};
            ZSTD_outBuffer o{z.data(), z.size(), 0};
            while (in.pos < in.size) ZSTD_compressStream2(c, &o, &in, ZSTD_e_continue);
            in.size = p.size();
            while (ZSTD_compressStream2(c, &o, &in, ZSTD_e_end) != 0) {}
            n = o.pos;
            ZSTD_freeCCtx(c);
        }
        if (ZSTD_isError(n)) throw std::runtime_error("zstd_frames: compression failed");
        out.append(z.data(), n);
    }
    return out;
}

// The text cut before every line starting "frame ": the header, then a piece a frame.
inline std::vector<std::string> by_frame(const std::string& text) {
    std::vector<std::string> pieces;
    std::size_t from = 0;
    for (std::size_t at = text.rfind("frame ", 0) == 0 ? 0 : text.find("\nframe "); at != std::string::npos;
         at = text.find("\nframe ", at + 1)) {
        const std::size_t start = text[at] == '\n' ? at + 1 : at;
        if (start > from) pieces.push_back(text.substr(from, start - from));
        from = start;
    }
    pieces.push_back(text.substr(from));
    return pieces;
}

} // namespace rbcd::test
