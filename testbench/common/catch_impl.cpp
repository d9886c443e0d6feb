// Catch's implementation, compiled once for both test mains (catch_main.cpp,
// catch_sc_main.cpp): it is the costliest file of the test tree to compile.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include "catch_run.h"

int rbcd_catch_run(int argc, char* argv[]) { return Catch::Session().run(argc, argv); }
