// MakeTransport for build/vismask: `loop` (one process, transport_loop.cpp)
// or `pipe` (forked ranks over POSIX pipes, transport_pipe.cpp), by the
// request; build/vismask-mpi links transport_mpi.cpp instead.
#include <memory>
#include <string>

#include "transport_local.h"
#include "vismask/parallel/transport.h"

namespace vismask {

std::unique_ptr<Transport> MakeTransport(const TransportRequest& request, Status* error) {
  const std::string& name = request.name;
  std::string tooMany = RankCountError(request.ranks, "--ranks");
  if (!tooMany.empty()) {
    *error = Status::Error(tooMany);
    return nullptr;
  }
  if (name == "mpi") {
    *error = Status::Error(
        "vismask: --transport mpi is in build/vismask-mpi (run it under mpirun); this binary "
        "has loop and pipe");
    return nullptr;
  }
  std::string loop = LoopTransportError(name, request.ranks);
  if (!loop.empty()) {
    *error = Status::Error(loop);
    return nullptr;
  }
  if (name == "loop" || (name.empty() && request.ranks == 1)) return MakeLoopTransport();
  if (name == "pipe" || name.empty()) {
    return MakePipeTransport(request.ranks, request.rankTimeout, error);
  }
  *error =
      Status::Error("vismask: unknown --transport '" + name + "' (this binary has loop and pipe)");
  return nullptr;
}

}  // namespace vismask
