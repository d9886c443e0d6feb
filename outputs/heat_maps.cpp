#include "rbcd/outputs/heat_maps.h"

#include <fcntl.h>
#include <png.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "rbcd/common/errors.h"
#include "rbcd/common/write_all.h"
#include "rbcd/hw/rbcd_system.h"

namespace rbcd {

namespace {

constexpr unsigned kScale = 2;                     // font pixels a glyph pixel
constexpr unsigned kCell = 12;                     // map pixels a tile (cell) side
constexpr unsigned kMargin = 10, kTitle = 24, kBar = 16, kLabels = 64;
constexpr unsigned char kBackground[3] = {255, 255, 255};
constexpr unsigned char kAbsent[3] = {200, 200, 200};   // no tile record there
constexpr unsigned char kInk[3] = {0, 0, 0};

// A 3x5 font for the titles and scale labels: five rows of three bits each,
// left pixel highest.
std::uint16_t glyph(char c) {
    static const char* const digits = "0123456789";
    static const std::uint16_t d[] = {075557, 026227, 071747, 071717, 055711, 074717, 074757, 071111, 075757, 075717};
    static const std::uint16_t a[] = {025755, 065656, 034443, 065556, 074647, 074644, 034553, 055755, 072227, 011152,
                                      055655, 044447, 057755, 065555, 025552, 065644, 025563, 065655, 034216, 072222,
                                      055557, 055552, 055775, 055255, 055222, 071247};
    if (const char* p = std::strchr(digits, c); p && c) return d[p - digits];
    if (c >= 'A' && c <= 'Z') return a[c - 'A'];
    if (c >= 'a' && c <= 'z') return a[c - 'a'];
    switch (c) {
    case '.': return 000002;
    case '-': return 000700;
    case '(': return 012221;
    case ')': return 042224;
    case '/': return 011244;
    case ':': return 002020;
    default: return 0;
    }
}

// Colour scale: dark blue (zero) through magenta and orange to light yellow
// (the maximum), brightness rising with the value so it reads in grey too.
void colour(double f, unsigned char out[3]) {
    static const double stops[][3] = {{20, 20, 80}, {120, 30, 140}, {220, 60, 80}, {250, 150, 40}, {255, 250, 180}};
    f = std::clamp(f, 0.0, 1.0) * 4.0;
    const int i = std::min(3, static_cast<int>(f));
    const double t = f - i;
    for (int c = 0; c < 3; ++c) out[c] = static_cast<unsigned char>(std::lround(stops[i][c] + t * (stops[i + 1][c] - stops[i][c])));
}

struct Canvas {
    unsigned w, h;
    std::vector<unsigned char> rgb;
    Canvas(unsigned width, unsigned height) : w(width), h(height), rgb(std::size_t(width) * height * 3) {
        for (std::size_t i = 0; i < rgb.size(); i += 3) std::memcpy(&rgb[i], kBackground, 3);
    }
    void put(unsigned x, unsigned y, const unsigned char c[3]) {
        if (x < w && y < h) std::memcpy(&rgb[(std::size_t(y) * w + x) * 3], c, 3);
    }
    void fill(unsigned x, unsigned y, unsigned fw, unsigned fh, const unsigned char c[3]) {
        for (unsigned j = 0; j < fh; ++j)
            for (unsigned i = 0; i < fw; ++i) put(x + i, y + j, c);
    }
    void text(unsigned x, unsigned y, const std::string& s) {
        for (char ch : s) {
            const std::uint16_t g = glyph(ch);
            for (unsigned r = 0; r < 5; ++r)
                for (unsigned c = 0; c < 3; ++c)
                    if (g >> ((4 - r) * 3 + (2 - c)) & 1) fill(x + c * kScale, y + r * kScale, kScale, kScale, kInk);
            x += 4 * kScale;
        }
    }
};

std::string number(double v) {
    char b[32];
    if ((v == std::floor(v) || std::fabs(v) >= 100) && std::fabs(v) < 1e15) std::snprintf(b, sizeof b, "%.0f", v);
    else std::snprintf(b, sizeof b, "%.3g", v);
    return b;
}

// A tEXt chunk inserted after IHDR (PNG: 8-byte signature, IHDR 25 bytes).
std::string with_text(const std::string& png, const std::string& key, const std::string& text) {
    std::string data = key + '\0' + text;
    std::string chunk;
    const std::uint32_t len = static_cast<std::uint32_t>(data.size());
    for (int i = 3; i >= 0; --i) chunk += static_cast<char>(len >> (8 * i) & 0xff);
    const std::string body = "tEXt" + data;
    chunk += body;
    const std::uint32_t crc = static_cast<std::uint32_t>(
        crc32(0, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size())));
    for (int i = 3; i >= 0; --i) chunk += static_cast<char>(crc >> (8 * i) & 0xff);
    return png.substr(0, 33) + chunk + png.substr(33);
}

// A map appears whole or not at all: written to an unpredictable temporary
// beside it (mkostemp) and renamed. Not an OutputFile: maps are written while
// the simulation runs, when OutputFile's interrupt list must not grow (its
// signal handler walks it); a kill mid-write can leave a hidden .NAME.XXXXXX,
// as docs/limits.md says of SIGKILL.
// Empty when written, else the one-line reason.
std::string write_whole(const std::string& path, const std::string& bytes) {
    const std::size_t slash = path.rfind('/');
    std::string tmp = (slash == std::string::npos ? std::string(".") : path.substr(0, slash)) + "/." +
                      (slash == std::string::npos ? path : path.substr(slash + 1)) + ".XXXXXX";
    const int fd = ::mkostemp(tmp.data(), O_CLOEXEC);
    if (fd < 0) return path + ": cannot create: " + std::strerror(errno);
    if (const int err = write_all(fd, bytes.data(), bytes.size())) {
        ::close(fd);
        ::unlink(tmp.c_str());
        return path + ": write failed: " + std::strerror(err);
    }
    const mode_t mask = ::umask(0);
    ::umask(mask);
    (void)::fchmod(fd, 0666 & ~mask);
    if (::close(fd) != 0 || ::rename(tmp.c_str(), path.c_str()) != 0) {
        const std::string why = std::strerror(errno);
        ::unlink(tmp.c_str());
        return path + ": write failed: " + why;
    }
    return {};
}

} // namespace

const char* HeatMaps::file_name(Metric m) {
    static const char* const n[] = {"stall", "overflow", "depth", "hits"};
    return n[m];
}

std::string HeatMaps::render(const std::vector<double>& values, unsigned cols, unsigned rows, Metric m,
                             const std::string& title) {
    static const char* const legend[] = {"stall cycles", "fragments dropped (overflow)",
                                         "collisionable depth complexity", "hits"};
    double hi = 0;
    for (double v : values)
        if (!std::isnan(v)) hi = std::max(hi, v);
    const unsigned map_w = cols * kCell, map_h = rows * kCell;
    const unsigned title_w = static_cast<unsigned>((title.size() + 3 + std::strlen(legend[m])) * 4 * kScale);
    const unsigned w = std::max(2 * kMargin + map_w + kMargin + kBar + kLabels, 2 * kMargin + title_w);
    const unsigned h = kTitle + std::max(map_h, 120u) + 2 * kMargin;
    Canvas cv(w, h);
    cv.text(kMargin, kMargin / 2, title + " - " + legend[m]);
    const unsigned y0 = kTitle;
    unsigned char c[3];
    for (unsigned r = 0; r < rows; ++r)
        for (unsigned col = 0; col < cols; ++col) {
            const double v = values[std::size_t(r) * cols + col];
            if (std::isnan(v)) {
                cv.fill(kMargin + col * kCell, y0 + r * kCell, kCell, kCell, kAbsent);
                continue;
            }
            colour(hi > 0 ? v / hi : 0, c);
            cv.fill(kMargin + col * kCell, y0 + r * kCell, kCell, kCell, c);
        }
    // The scale: a bar from 0 (bottom) to the maximum (top), three labels.
    const unsigned bx = kMargin + map_w + kMargin, bh = std::max(map_h, 120u);
    for (unsigned j = 0; j < bh; ++j) {
        colour(1.0 - double(j) / (bh - 1), c);
        cv.fill(bx, y0 + j, kBar, 1, c);
    }
    cv.text(bx + kBar + 4, y0, number(hi));
    cv.text(bx + kBar + 4, y0 + bh / 2 - 5, number(hi / 2));
    cv.text(bx + kBar + 4, y0 + bh - 10, "0");

    png_image img{};
    img.version = PNG_IMAGE_VERSION;
    img.width = w;
    img.height = h;
    img.format = PNG_FORMAT_RGB;
    png_alloc_size_t size = 0;
    if (!png_image_write_to_memory(&img, nullptr, &size, 0, cv.rgb.data(), png_int_32(w * 3), nullptr))
        throw RunError(std::string("heat map: cannot encode: ") + img.message);
    std::string png(size, '\0');
    if (!png_image_write_to_memory(&img, png.data(), &size, 0, cv.rgb.data(), png_int_32(w * 3), nullptr))
        throw RunError(std::string("heat map: cannot encode: ") + img.message);
    png.resize(size);
    // The values: "cols rows", then a line a row; "-" where no tile was.
    std::string text = std::to_string(cols) + " " + std::to_string(rows) + "\n";
    for (unsigned r = 0; r < rows; ++r) {
        for (unsigned col = 0; col < cols; ++col) {
            const double v = values[std::size_t(r) * cols + col];
            char b[32];
            if (std::isnan(v)) std::snprintf(b, sizeof b, "-");
            else std::snprintf(b, sizeof b, "%.17g", v);
            text += (col ? " " : "") + std::string(b);
        }
        text += "\n";
    }
    return with_text(png, "rbcd-heat-map", text);
}

HeatMaps::HeatMaps(std::string dir, bool per_frame, unsigned screen_w, unsigned screen_h, unsigned tile_w,
                   unsigned tile_h)
    : dir_(std::move(dir)), per_frame_(per_frame), cols_((screen_w + tile_w - 1) / tile_w),
      rows_((screen_h + tile_h - 1) / tile_h), tile_pixels_(tile_w * tile_h) {
    for (Grid* g : {&frame_, &run_})
        for (auto& v : g->v) v.assign(std::size_t(cols_) * rows_, NAN);
}

HeatMaps::~HeatMaps() {
    if (keep_) return;
    for (const auto& f : written_) ::unlink(f.c_str());
}

void HeatMaps::attach(rbcd_system& sys) {
    sys.raster.add_tile_observer(this);
    sys.tester.add_test_observer(this);
}

double& HeatMaps::at(Grid& g, Metric m, std::uint32_t col, std::uint32_t row) {
    if (col >= cols_ || row >= rows_) {
        // A tile off the declared screen: the maps grow to hold it.
        const unsigned nc = std::max(cols_, col + 1), nr = std::max(rows_, row + 1);
        for (Grid* gr : {&frame_, &run_})
            for (auto& v : gr->v) {
                std::vector<double> grown(std::size_t(nc) * nr, NAN);
                for (unsigned r = 0; r < rows_; ++r)
                    for (unsigned c = 0; c < cols_; ++c) grown[std::size_t(r) * nc + c] = v[std::size_t(r) * cols_ + c];
                v.swap(grown);
            }
        cols_ = nc;
        rows_ = nr;
    }
    double& v = g.v[m][std::size_t(row) * cols_ + col];
    if (std::isnan(v)) v = 0;
    return v;
}

void HeatMaps::tile_fed(const TileTimes& t) {
    const double stall = double(t.stall_no_bank + t.stall_queue_full + t.stall_fragment_queue);
    for (Grid* g : {&frame_, &run_}) {
        at(*g, Stall, t.col, t.row) += stall;
        at(*g, Depth, t.col, t.row) += double(t.fragments);
        at(*g, Overflow, t.col, t.row) += 0;
        at(*g, Hits, t.col, t.row) += 0;
    }
}

void HeatMaps::tile_tested(const TestedTile& t) {
    for (Grid* g : {&frame_, &run_}) {
        at(*g, Stall, t.col, t.row) += double(t.output_stall);
        at(*g, Overflow, t.col, t.row) += double(t.fragments_dropped);
        at(*g, Hits, t.col, t.row) += double(t.hits);
    }
}

void HeatMaps::write(const Grid& g, const std::string& name, const std::string& title, double depth_scale) {
    for (int m = 0; m < kMetrics; ++m) {
        std::vector<double> v = g.v[m];
        if (m == Depth)
            for (double& x : v) x = std::isnan(x) ? x : x / depth_scale;
        if (!error_.empty()) return;
        const std::string path = dir_ + "/" + name + "_" + file_name(Metric(m)) + ".png";
        error_ = write_whole(path, render(v, cols_, rows_, Metric(m), title));
        if (error_.empty()) written_.push_back(path);
    }
}

void HeatMaps::frame_end(const FrameTimes& f) {
    ++frames_;
    if (per_frame_) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%05llu", static_cast<unsigned long long>(f.frame));
        write(frame_, name, "frame " + std::to_string(f.frame), tile_pixels_);
    }
    for (auto& v : frame_.v) std::fill(v.begin(), v.end(), NAN);
}

void HeatMaps::finish() {
    // Depth over the run: the mean over its frames.
    write(run_, "run", "run of " + std::to_string(frames_) + " frames", double(tile_pixels_) * std::max<std::uint64_t>(frames_, 1));
}

} // namespace rbcd
