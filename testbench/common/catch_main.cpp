// The main of the test binaries without SystemC.
#include "catch_run.h"

int main(int argc, char* argv[]) { return rbcd_catch_run(argc, argv); }
