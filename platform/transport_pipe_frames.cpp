// The pipe transport's frame pump (pipe_internal.h): Pump moves every
// active frame to and from all peers at once, polling the pipes, and
// watches each awaited peer's silence against the wait limit; WriteSome,
// ReadSome and AcceptWord write and read the framed messages.
#include <errno.h>
#include <poll.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>

#include "pipe_internal.h"
#include "rank_wait.h"
#include "vismask/core/check.h"
#include "vismask/core/os.h"

namespace vismask {
namespace {

// How long a waiting rank sleeps in poll() before it checks that its peers live.
constexpr int kPollMs = 100;

const char* ErrnoReason(int err) {
  if (err == EPIPE) return "broken pipe";
  if (err == ECONNRESET) return "connection reset";
  return std::strerror(err);
}

}  // namespace

void PipeTransport::AcceptWord(int peer) {
  InFrame& f = in_[peer];
  if (f.atFinish) {
    if (f.word == kFinishWord) {
      f.bytes = kWordBytes;
    } else {
      f.outOfStep = true;
      f.active = false;
    }
    return;
  }
  if (f.word == kFinishWord) Lost(peer, "it finished while this rank still expected data");
  f.bytes = f.word;
  if (f.exact && f.bytes != f.capacity) {
    os::PrintErr("vismask: rank %d: rank %d sent %llu bytes, %llu expected\n", rank_, peer,
                 static_cast<unsigned long long>(f.bytes),
                 static_cast<unsigned long long>(f.capacity));
    CHECK_MSG(false, "Send/Recv sizes disagree");
  }
  if (f.bytes > f.capacity) {
    os::PrintErr("vismask: rank %d: rank %d sent %llu bytes, the buffer holds %llu\n", rank_, peer,
                 static_cast<unsigned long long>(f.bytes),
                 static_cast<unsigned long long>(f.capacity));
    CHECK_MSG(false, "receive buffer too small");
  }
}

void PipeTransport::WriteSome(int peer) {
  OutFrame& f = out_[peer];
  const uint64_t total = kWordBytes + f.bytes;
  while (f.done < total) {
    iovec iov[2];
    int count = 0;
    if (f.done < kWordBytes) {
      iov[count++] = {reinterpret_cast<uint8_t*>(&f.word) + f.done,
                      static_cast<size_t>(kWordBytes - f.done)};
      if (f.bytes > 0) iov[count++] = {const_cast<uint8_t*>(f.data), static_cast<size_t>(f.bytes)};
    } else {
      uint64_t sent = f.done - kWordBytes;
      iov[count++] = {const_cast<uint8_t*>(f.data) + sent, static_cast<size_t>(f.bytes - sent)};
    }
    ssize_t w = ::writev(peers_[peer].writeFd, iov, count);
    if (w < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) return;
      Lost(peer, ErrnoReason(errno));
    }
    f.done += static_cast<uint64_t>(w);
  }
  f.active = false;
}

void PipeTransport::ReadSome(int peer) {
  InFrame& f = in_[peer];
  for (;;) {
    if (f.done >= kWordBytes && f.done - kWordBytes == f.bytes) {
      f.active = false;
      return;
    }
    ssize_t r;
    if (f.done < kWordBytes) {
      r = ::read(peers_[peer].readFd, reinterpret_cast<uint8_t*>(&f.word) + f.done,
                 kWordBytes - f.done);
    } else {
      uint64_t got = f.done - kWordBytes;
      r = ::read(peers_[peer].readFd, f.data + got, f.bytes - got);
    }
    if (r < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) return;
      Lost(peer, ErrnoReason(errno));
    }
    if (r == 0) {
      if (f.atFinish) {
        f.eof = true;
        f.active = false;
        return;
      }
      Lost(peer, "connection closed");
    }
    bool hadWord = f.done >= kWordBytes;
    f.done += static_cast<uint64_t>(r);
    if (!hadWord && f.done == kWordBytes) {
      AcceptWord(peer);
      if (!f.active) return;
    }
  }
}

void PipeTransport::Pump(bool atFinish) {
  const double start = os::Seconds();
  const double limit = WaitLimit();
  double lastTurn = start;
  for (int p = 0; p < size_; ++p) heard_[p] = start;
  for (;;) {
    int n = 0;
    for (int p = 0; p < size_; ++p) {
      if (out_[p].active) {
        pollFds_[n] = {peers_[p].writeFd, POLLOUT, 0};
        pollPeer_[n++] = p;
      }
      if (in_[p].active) {
        pollFds_[n] = {peers_[p].readFd, POLLIN, 0};
        pollPeer_[n++] = p + kMaxPipeRanks;
      }
    }
    if (n == 0) {
      NoteWait(os::Seconds() - start);
      return;
    }
    int ready = ::poll(pollFds_, static_cast<nfds_t>(n), kPollMs);
    if (ready < 0) CHECK_MSG(errno == EINTR, "poll failed");
    const double now = os::Seconds();
    // This rank was not running: its peers' silence is not theirs.
    if (now - lastTurn > kStoppedGap) {
      for (int p = 0; p < size_; ++p) heard_[p] = now;
    }
    lastTurn = now;
    if (ready == 0) {
      // At Finish, children are expected to exit: EOF tells the rest.
      if (!atFinish) CheckPeers();
    }
    for (int i = 0; ready > 0 && i < n; ++i) {
      if (pollFds_[i].revents == 0) continue;
      int peer = pollPeer_[i] % kMaxPipeRanks;
      heard_[peer] = now;
      if (pollPeer_[i] < kMaxPipeRanks) {
        WriteSome(peer);
      } else {
        ReadSome(peer);
      }
    }
    if (limit <= 0.0) continue;
    // A peer silent for longer than the limit ends the run; one this rank
    // waits to read from is named before one it only writes to.
    for (int pass = 0; pass < 2; ++pass) {
      for (int p = 0; p < size_; ++p) {
        bool awaited = pass == 0 ? in_[p].active : out_[p].active;
        if (awaited && now - heard_[p] > limit) Silent(p, pass == 0, limit);
      }
    }
  }
}

}  // namespace vismask
