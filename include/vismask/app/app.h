// The vismask command line as a function: parses, initialises, solves and
// writes the outputs. Returns the process exit status (0 ok, 1 an output could
// not be written, 2 bad input or options, 4 the solve stalled); never calls exit(), so tests can
// run it in-process. Sets the render Phase (phase.h) as it goes.
#pragma once

namespace vismask {

int Main(int argc, const char* const* argv);

}  // namespace vismask
