// FST waveforms (GTKWave's compressed format) written through fstapi, the
// writer GTKWave maintains; the build compiles it from the sources Debian's
// verilator package ships (/usr/share/verilator/include/gtkwave, MIT; its
// LZ4 is BSD-2-Clause, FastLZ MIT). Without them rbcd-sim is built without
// FST and --fst says so (docs/waveforms.md).
//
//   OutputFile out(path, OutputFile::ByName{});
//   FstWriter fst(out.library_path(), path);
//   VcdWriter wave(fst, period_ps, start, end);   // same signals and window as a VCD
//   ... run ...
//   fst.close();  out.commit();
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "rbcd/common/vcd_writer.h"

namespace rbcd {

// True when this build has fstapi.
bool fst_supported();

class FstWriter final : public WaveEncoder {
public:
    // Creates the file at `path`; InputError when it cannot, or when the
    // build has no FST support. Messages name the file `name` (the user's path).
    FstWriter(const std::string& path, std::string name);
    ~FstWriter() override;
    FstWriter(const FstWriter&) = delete;
    FstWriter& operator=(const FstWriter&) = delete;

    void begin(const std::string& date, const std::string& version, std::uint64_t period_ps) override;
    void scope(const std::string& name) override;
    void upscope() override;
    void var(unsigned sig, const std::string& name, unsigned width) override;
    void end_definitions() override {}
    void time(std::uint64_t ps) override;
    void value(unsigned sig, unsigned width, std::uint64_t v) override;
    void finish() override {}

    // Writes the file's tail and checks it is whole (fstapi does not report
    // write errors): std::runtime_error naming the path when it is not.
    void close();

private:
    void* ctx_ = nullptr;
    std::string path_, name_;
    std::vector<std::uint32_t> handles_;   // by VcdWriter signal
};

// Checks an FST file's block chain: every block's length leads to the next and
// the last ends at the end of the file, with the hierarchy and geometry present.
// Empty when whole, else what is wrong.
std::string fst_check_file(const std::string& path);

} // namespace rbcd
