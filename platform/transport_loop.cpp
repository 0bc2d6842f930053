// The loop transport of build/vismask: one process, every collective a copy.
#include <cstring>
#include <memory>

#include "transport_local.h"
#include "vismask/core/check.h"
#include "vismask/parallel/transport.h"

namespace vismask {
namespace {

// One process: every collective is a copy, and there is nobody to send to.
class LoopTransport final : public Transport {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  const char* name() const override { return "loop"; }

  void AllToAll(const Span<const uint8_t>*, const Span<uint8_t>*, size_t* recvBytes) override {
    recvBytes[0] = 0;
  }
  void AllGather(const void* mine, size_t bytes, void* all) override {
    if (all != mine && bytes > 0) std::memmove(all, mine, bytes);
  }
  void Send(int, const void*, size_t) override {
    CHECK_MSG(false, "the loop transport has no other rank to send to");
  }
  void Recv(int, void*, size_t) override {
    CHECK_MSG(false, "the loop transport has no other rank to receive from");
  }
  int Finish(int exitCode) override { return exitCode; }
};

}  // namespace

std::unique_ptr<Transport> MakeLoopTransport() {
  return std::make_unique<LoopTransport>();
}

}  // namespace vismask
