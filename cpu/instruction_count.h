// rbcd-cpucd --count-instructions: the detection's executed instructions per
// section, counted by valgrind's callgrind (docs/cpucd.md, "Counted work").
// The program re-runs itself under callgrind with collection and
// instrumentation off. Around each frame's detection it switches
// instrumentation on and off; inside, around each measured section,
// collection, and has callgrind dump the section's count to a private
// directory, which it reads back at once (a client-request dump is written
// before the request returns).
#pragma once
#include <cstdint>
#include <istream>
#include <string>

#include "rbcd/cpu/cpu_collision.h"

namespace rbcd::cpucd {

// Built with valgrind/callgrind.h (Debian's valgrind package).
bool callgrind_compiled_in();
// This process runs under valgrind, started by run_under_callgrind.
bool counting_under_callgrind();

// Routes Bullet's allocations (btAlignedAlloc, which every Bullet object and
// array uses) to a heap of this program's own whose addresses follow from the
// sequence of requests alone. Bullet's dynamic tree orders nodes by address
// (btDbvt::optimizeIncremental), so with malloc's addresses, which depend on
// everything allocated before (the paths on the command line among them), the
// tree and the instructions it executes would change with the directory the
// input lies in. Call first thing, before Bullet allocates anything; in a
// counted run only.
void use_deterministic_bullet_heap();

// Runs this program (/proc/self/exe, argv as given) under
// `valgrind --tool=callgrind` with collection off and a private dump
// directory, and returns its exit status. Throws InputError when the counts
// cannot be taken: built without callgrind.h, or no valgrind on PATH.
int run_under_callgrind(int argc, char* argv[]);

// A callgrind dump (written with --compress-strings=no --compress-pos=no):
// its total Ir, and the part spent in the memory allocator (malloc, free,
// operator new and delete and the like, inclusive, called from outside it).
// The allocator's path depends on the heap's history, which the lengths of
// the paths on the command line change: the counts rbcd-cpucd reports leave
// it out, so that one input gives one count wherever it lies.
struct CallgrindCounts {
    std::uint64_t total = 0, allocator = 0;
    bool has_total = false;
};
CallgrindCounts parse_callgrind_dump(std::istream& in);
bool is_allocator_function(const std::string& name);

class CallgrindCounter : public SectionCounter {
public:
    CallgrindCounter();   // under callgrind only (counting_under_callgrind())
    // Callgrind's instrumentation on or off. It starts off: only code run
    // with it on can be counted (start() and stop() inside), and code runs
    // about ten times faster without it. Switching discards every
    // translation made so far, so it is switched once around a frame's
    // detection, not around each section. The counts do not depend on it:
    // a section's instructions are the same whatever ran uninstrumented
    // before it.
    void instrument(bool on);
    void start() override;
    std::uint64_t stop(Section s) override;

private:
    std::string prefix_;   // callgrind's --callgrind-out-file: dumps are PREFIX.1, PREFIX.2, ...
    unsigned dumps_ = 0;
};

} // namespace rbcd::cpucd
