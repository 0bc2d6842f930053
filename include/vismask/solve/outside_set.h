// OutsideSet: an environment's outside shooters (--sky, --sun; outside.h)
// with their unshot power and shot counts, carved from its arena (Layout) so
// that a checkpoint's bytes hold them.
#pragma once
#include <cstdint>
#include <vector>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/solve/ledger.h"
#include "vismask/solve/outside.h"

namespace vismask {

class OutsideSet {
 public:
  struct Entry {
    OutsideShooter shooter;
    double unshot[3];
    uint32_t shots;
  };
  // Room for `count` shooters (also from a measuring arena; none for 0).
  void Layout(Arena& arena, uint32_t count);
  // The shooters, copied field by field so that the padding keeps the
  // arena's zeros (a checkpoint holds the arena's bytes); nothing unshot.
  void Fill(const std::vector<OutsideShooter>& shooters);
  // Each shooter's whole power unshot and no shots, its power booked in
  // `ledger` as emitted, unshot and radiosity power (as an emitter's is).
  void Reset(EnergyLedger* ledger);
  // The shooter with the most unshot power (ties to the first), or -1 when
  // none has any.
  int Best() const;

  uint32_t size() const { return static_cast<uint32_t>(entries_.size()); }
  Entry& operator[](uint32_t k) { return entries_[k]; }
  const Entry& operator[](uint32_t k) const { return entries_[k]; }

 private:
  Span<Entry> entries_;
};

}  // namespace vismask
