#include "rbcd/outputs/fst_writer.h"

#include <cstdio>
#include <stdexcept>

#include "rbcd/common/errors.h"

#ifdef RBCD_HAVE_FST
extern "C" {
#include "fstapi.h"
}
#endif

namespace rbcd {

std::string fst_check_file(const std::string& path) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) return "cannot be read back";
    std::fseek(f, 0, SEEK_END);
    const long size = std::ftell(f);
    // Blocks: a type byte, then a big-endian 64-bit length counting itself and
    // the payload (docs/waveforms.md). 0 header, 3 geometry, 4/6/7 hierarchy.
    long at = 0;
    bool header = false, geometry = false, hierarchy = false;
    std::string why;
    while (at < size) {
        unsigned char b[9];
        if (std::fseek(f, at, SEEK_SET) != 0 || std::fread(b, 1, 9, f) != 9) {
            why = "a block is cut short at byte " + std::to_string(at);
            break;
        }
        std::uint64_t len = 0;
        for (int i = 1; i < 9; ++i) len = len << 8 | b[i];
        if (len < 8 || len > static_cast<std::uint64_t>(size - at - 1)) {
            why = "a block at byte " + std::to_string(at) + " runs past the end";
            break;
        }
        if (b[0] == 0) header = at == 0;
        if (b[0] == 3) geometry = true;
        if (b[0] == 4 || b[0] == 6 || b[0] == 7) hierarchy = true;
        at += 1 + static_cast<long>(len);
    }
    std::fclose(f);
    if (why.empty() && !(header && geometry && hierarchy)) why = "no header, geometry or hierarchy block";
    return why;
}

#ifdef RBCD_HAVE_FST

bool fst_supported() { return true; }

FstWriter::FstWriter(const std::string& path, std::string name) : path_(path), name_(std::move(name)) {
    ctx_ = fstWriterCreate(path.c_str(), 1);
    if (!ctx_) throw InputError(name_ + ": cannot create the FST file");
    fstWriterSetPackType(ctx_, FST_WR_PT_LZ4);
}

FstWriter::~FstWriter() {
    if (ctx_) fstWriterClose(ctx_);   // a failed run: the caller discards the file
}

void FstWriter::begin(const std::string& date, const std::string& version, std::uint64_t period_ps) {
    fstWriterSetDate(ctx_, date.c_str());
    fstWriterSetVersion(ctx_, version.c_str());
    fstWriterSetComment(ctx_, ("one cycle = " + std::to_string(period_ps) + " ps").c_str());
    fstWriterSetTimescale(ctx_, -12);   // 1 ps, as the VCD
}

void FstWriter::scope(const std::string& name) {
    fstWriterSetScope(ctx_, FST_ST_VCD_MODULE, name.c_str(), nullptr);
}

void FstWriter::upscope() { fstWriterSetUpscope(ctx_); }

void FstWriter::var(unsigned sig, const std::string& name, unsigned width) {
    if (handles_.size() <= sig) handles_.resize(sig + 1, 0);
    // A vector's range goes in its name, as in the VCD's $var: viewers show
    // and save files name it "state[1:0]" in either format.
    const std::string full = width > 1 ? name + " [" + std::to_string(width - 1) + ":0]" : name;
    handles_[sig] = fstWriterCreateVar(ctx_, FST_VT_VCD_WIRE, FST_VD_IMPLICIT, width, full.c_str(), 0);
}

void FstWriter::time(std::uint64_t ps) { fstWriterEmitTimeChange(ctx_, ps); }

void FstWriter::value(unsigned sig, unsigned width, std::uint64_t v) {
    fstWriterEmitValueChange64(ctx_, handles_[sig], width, v);
}

void FstWriter::close() {
    if (!ctx_) return;
    fstWriterClose(ctx_);
    ctx_ = nullptr;
    if (const std::string why = fst_check_file(path_); !why.empty())
        throw std::runtime_error(name_ + ": write failed: the FST file is incomplete (" + why + ")");
}

#else

bool fst_supported() { return false; }

FstWriter::FstWriter(const std::string&, std::string) {
    throw InputError("--fst: this rbcd-sim was built without FST support (install Debian's verilator package: "
                     "scripts/setup.sh --waves, then rebuild)");
}
FstWriter::~FstWriter() = default;
void FstWriter::begin(const std::string&, const std::string&, std::uint64_t) {}
void FstWriter::scope(const std::string&) {}
void FstWriter::upscope() {}
void FstWriter::var(unsigned, const std::string&, unsigned) {}
void FstWriter::time(std::uint64_t) {}
void FstWriter::value(unsigned, unsigned, std::uint64_t) {}
void FstWriter::close() {}

#endif

} // namespace rbcd
