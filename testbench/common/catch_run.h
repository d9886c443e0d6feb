#pragma once
// Runs Catch's session (catch_impl.cpp, the implementation compiled once for
// both test mains: Catch declares its Session only beside the implementation).
int rbcd_catch_run(int argc, char* argv[]);
