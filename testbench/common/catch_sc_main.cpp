// libsystemc.so defines main() and calls sc_main(): Catch runs from there.
#include <cstdlib>
#include <systemc>

#include "catch_run.h"
#include "rbcd/run/sanitizer_stack.h"

namespace {
// The kernel prints its banner before sc_main runs, once per test process:
// dozens of copies in a ctest log and in catch_discover_tests at build time.
// Static initialisation of the program comes first (as in rbcd-sim).
const bool banner_off = [] { return ::setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0) == 0; }();
} // namespace

int sc_main(int argc, char* argv[]) {
    // The tests' simulations leave the main thread's stack recorded as a
    // coroutine's for LeakSanitizer's scan at exit: recorded again here.
    const rbcd::MainStackForSanitizer main_stack;
    return rbcd_catch_run(argc, argv);
}
