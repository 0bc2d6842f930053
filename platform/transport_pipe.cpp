// The pipe transport of build/vismask (pipe_internal.h): ranks forked from
// the calling process, one POSIX pipe per ordered pair of ranks. This file
// holds the collectives, each a set of frames handed to the pump
// (transport_pipe_frames.cpp), and MakePipeTransport; the ranks' lifecycle
// and Finish are in transport_pipe_process.cpp.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>

#include "pipe_internal.h"
#include "transport_local.h"
#include "vismask/core/check.h"
#include "vismask/core/span.h"
#include "vismask/core/status.h"
#include "vismask/parallel/transport.h"

namespace vismask {

void PipeTransport::AllToAll(const Span<const uint8_t>* send, const Span<uint8_t>* recv,
                             size_t* recvBytes) {
  CHECK_MSG(!finished_, "transport used after Finish");
  CheckPeers();
  for (int p = 0; p < size_; ++p) {
    if (p == rank_) continue;
    out_[p] = OutFrame();
    out_[p].active = true;
    out_[p].word = send[p].size();
    out_[p].data = send[p].data();
    out_[p].bytes = send[p].size();
    in_[p] = InFrame();
    in_[p].active = true;
    in_[p].data = recv[p].data();
    in_[p].capacity = recv[p].size();
  }
  Pump(false);
  for (int p = 0; p < size_; ++p) recvBytes[p] = p == rank_ ? 0 : in_[p].bytes;
}

void PipeTransport::AllGather(const void* mine, size_t bytes, void* all) {
  uint8_t* allBytes = static_cast<uint8_t*>(all);
  for (int p = 0; p < size_; ++p) {
    gatherSend_[p] = Span<const uint8_t>(static_cast<const uint8_t*>(mine), bytes);
    gatherRecv_[p] = Span<uint8_t>(allBytes + static_cast<size_t>(p) * bytes, bytes);
  }
  AllToAll(gatherSend_, gatherRecv_, gatherBytes_);
  for (int p = 0; p < size_; ++p) {
    if (p != rank_) CHECK_MSG(gatherBytes_[p] == bytes, "AllGather block sizes disagree");
  }
  uint8_t* own = allBytes + static_cast<size_t>(rank_) * bytes;
  if (own != mine && bytes > 0) std::memmove(own, mine, bytes);
}

void PipeTransport::PointToPoint(int peer, void* data, size_t bytes, bool recv) {
  CheckPeers();
  if (recv) {
    in_[peer] = InFrame();
    in_[peer].active = true;
    in_[peer].exact = true;
    in_[peer].data = static_cast<uint8_t*>(data);
    in_[peer].capacity = bytes;
  } else {
    out_[peer] = OutFrame();
    out_[peer].active = true;
    out_[peer].word = bytes;
    out_[peer].data = static_cast<const uint8_t*>(data);
    out_[peer].bytes = bytes;
  }
  Pump(false);
}

std::unique_ptr<Transport> MakePipeTransport(int ranks, double rankTimeout, Status* error) {
  auto transport = std::make_unique<PipeTransport>();
  Status s = transport->Start(ranks, rankTimeout);
  if (!s.ok()) {
    *error = s;
    return nullptr;
  }
  return transport;
}

}  // namespace vismask
