// The two transports of build/vismask, for its MakeTransport
// (transport_posix.cpp).
#pragma once
#include <memory>

#include "vismask/core/status.h"
#include "vismask/parallel/transport.h"

namespace vismask {

// One process: every collective is a copy (transport_loop.cpp).
std::unique_ptr<Transport> MakeLoopTransport();

// `ranks` processes forked from this one, one POSIX pipe per ordered pair
// (transport_pipe.cpp); null with *error on failure.
std::unique_ptr<Transport> MakePipeTransport(int ranks, double rankTimeout, Status* error);

}  // namespace vismask
