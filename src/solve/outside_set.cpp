// OutsideSet: its layout, fill, reset and choice of shooter.
#include "vismask/solve/outside_set.h"

namespace vismask {

void OutsideSet::Layout(Arena& arena, uint32_t count) {
  if (count > 0) entries_ = arena.Alloc<Entry>(count);
}

void OutsideSet::Fill(const std::vector<OutsideShooter>& shooters) {
  for (uint32_t k = 0; k < size(); ++k) {
    Entry& o = entries_[k];
    o.shooter.patch = shooters[k].patch;
    o.shots = 0;
    for (int c = 0; c < 3; ++c) {
      o.shooter.power[c] = shooters[k].power[c];
      o.unshot[c] = 0.0;
    }
  }
}

void OutsideSet::Reset(EnergyLedger* ledger) {
  for (uint32_t k = 0; k < size(); ++k) {
    Entry& o = entries_[k];
    o.shots = 0;
    for (int c = 0; c < 3; ++c) {
      o.unshot[c] = o.shooter.power[c];
      ledger->emitted[c] += o.unshot[c];
      ledger->unshot[c] += o.unshot[c];
      ledger->radiosity[c] += o.unshot[c];
    }
  }
}

int OutsideSet::Best() const {
  int best = -1;
  double key = 0.0;
  for (uint32_t k = 0; k < size(); ++k) {
    const double* u = entries_[k].unshot;
    const double s = u[0] + u[1] + u[2];
    if (s > key) {
      key = s;
      best = static_cast<int>(k);
    }
  }
  return best;
}

}  // namespace vismask
