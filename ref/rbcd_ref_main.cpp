// rbcd-ref: the untimed reference model on a trace, writing the collision file
// of formats.md. It exists so that golden vectors are checked by two
// independent implementations of the contract, and so that a disagreement with
// rbcd-sim can be reproduced outside SystemC.
//
//   rbcd-ref --trace FILE [--config FILE] [--set KEY=VALUE]... --collisions OUT
//
// Exit status as rbcd-sim's: 0 done, 2 bad input/configuration/command line,
// 1 anything else. On a non-zero exit no file is left at OUT, not even an older one.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/errors.h"
#include "rbcd/io/collision_format.h"
#include "rbcd/io/trace_reader.h"
#include "rbcd/ref/reference_model.h"

namespace {

const char* const kUsage =
    "usage: rbcd-ref --trace FILE [--config FILE] [--set KEY=VALUE]... --collisions OUT\n";

struct Args {
    std::string trace, config, collisions;
    std::vector<std::string> sets;
};

Args parse_args(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        const std::string opt = argv[i];
        if (opt == "--help" || opt == "-h") {
            std::cout << kUsage;
            std::exit(0);
        }
        if (i + 1 >= argc) throw rbcd::InputError("command line: " + opt + " needs a value (or is unknown)");
        const std::string val = argv[++i];
        if (opt == "--trace") a.trace = val;
        else if (opt == "--config") a.config = val;
        else if (opt == "--set") a.sets.push_back(val);
        else if (opt == "--collisions") a.collisions = val;
        else throw rbcd::InputError("command line: unknown option " + opt);
    }
    if (a.trace.empty()) throw rbcd::InputError("command line: --trace FILE is required");
    if (a.collisions.empty()) throw rbcd::InputError("command line: --collisions OUT is required");
    return a;
}

std::string collision_text(const rbcd::ref::RefResult& r) {
    std::string s = rbcd::kCollisionsMagic;
    for (const auto& f : r.frames) {
        rbcd::append_frame_line(s, f.frame);
        for (const auto& rec : f.records) {
            if (const auto* h = std::get_if<rbcd::HitRecord>(&rec)) rbcd::append_hit_line(s, *h);
            else rbcd::append_overflow_line(s, std::get<rbcd::OverflowRecord>(rec));
        }
    }
    return s;
}

// Written beside OUT and renamed over it, so that OUT is either complete or absent.
void write_file(const std::string& path, const std::string& text) {
    const std::string tmp = path + ".tmp";
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw rbcd::InputError(path + ": cannot create");
    const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    if (std::fclose(f) != 0 || !ok) {
        std::remove(tmp.c_str());
        throw std::runtime_error(path + ": write error");
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        std::remove(tmp.c_str());
        throw rbcd::InputError(path + ": cannot create");
    }
}

} // namespace

int main(int argc, char** argv) {
    std::string out_path;
    try {
        // Learn OUT before anything can fail, so that an older file there is removed on error.
        for (int i = 1; i + 1 < argc; ++i)
            if (std::string(argv[i]) == "--collisions") out_path = argv[i + 1];
        const Args args = parse_args(argc, argv);

        rbcd::SimConfig sim;
        if (!args.config.empty()) rbcd::apply_config_file(sim, args.config);
        for (const auto& s : args.sets) rbcd::apply_config_set(sim, s);
        sim.validate();

        rbcd::TraceLimits limits;
        limits.tile_w = sim.tile.width;
        limits.tile_h = sim.tile.height;
        limits.id_bits = sim.zeb.id_bits;
        rbcd::TraceReader reader(args.trace, limits);

        const auto cfg = rbcd::ref::ref_config_from(sim, reader.header().depth_bits);
        const auto result = rbcd::ref::run_reference(cfg, reader);
        write_file(args.collisions, collision_text(result));
        return 0;
    } catch (const rbcd::InputError& e) {
        if (!out_path.empty()) std::remove(out_path.c_str());
        std::cerr << "rbcd-ref: " << e.what() << '\n';
        if (std::string(e.what()).rfind("command line:", 0) == 0) std::cerr << kUsage;
        return 2;
    } catch (const std::exception& e) {
        if (!out_path.empty()) std::remove(out_path.c_str());
        std::cerr << "rbcd-ref: " << e.what() << '\n';
        return 1;
    }
}
