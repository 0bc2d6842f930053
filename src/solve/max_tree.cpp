#include "vismask/solve/max_tree.h"

namespace vismask {

void MaxTree::Layout(Arena& arena, uint32_t n, bool ties) {
  n_ = n;
  leaves_ = 1;
  while (leaves_ < n) leaves_ <<= 1;
  key_ = arena.Alloc<double>(n);
  tie_ = arena.Alloc<uint64_t>(ties ? n : 0);
  node_ = arena.Alloc<uint32_t>(n == 0 ? 0 : leaves_ < 2 ? 2 : leaves_);
}

uint32_t MaxTree::Winner(uint32_t a, uint32_t b) const {
  if (a == kNoPatch) return b;
  if (b == kNoPatch) return a;
  if (key_[b] > key_[a]) return b;
  if (key_[a] > key_[b]) return a;
  if (!tie_.empty() && tie_[a] != tie_[b]) return tie_[a] < tie_[b] ? a : b;
  return a < b ? a : b;
}

void MaxTree::Clear(double key) {
  for (uint32_t i = 0; i < n_; ++i) key_[i] = key;
  for (uint64_t& t : tie_) t = 0;
  if (n_ == 0) return;
  if (leaves_ == 1) {
    node_[1] = n_ == 1 ? 0 : kNoPatch;
    return;
  }
  // Bottom level of internal nodes from the implicit leaves, then upwards.
  for (uint32_t v = leaves_ / 2; v < leaves_; ++v) {
    uint32_t a = 2 * v - leaves_, b = a + 1;
    node_[v] = Winner(a < n_ ? a : kNoPatch, b < n_ ? b : kNoPatch);
  }
  for (uint32_t v = leaves_ / 2 - 1; v >= 1; --v) node_[v] = Winner(node_[2 * v], node_[2 * v + 1]);
}

void MaxTree::Set(uint32_t i, double key) {
  DCHECK(i < n_);
  key_[i] = key;
  if (leaves_ == 1) return;
  uint32_t v = (leaves_ + i) >> 1;
  uint32_t a = 2 * v - leaves_, b = a + 1;
  node_[v] = Winner(a, b < n_ ? b : kNoPatch);
  for (v >>= 1; v >= 1; v >>= 1) node_[v] = Winner(node_[2 * v], node_[2 * v + 1]);
}

void MaxTree::Increase(uint32_t i, double key) {
  DCHECK(i < n_ && key >= key_[i]);
  key_[i] = key;
  // Each node holds its subtree's winner; a larger key for i can only make
  // i the winner on some prefix of its path to the root, so stop at the
  // first node that i does not win.
  for (uint32_t v = (leaves_ + i) >> 1; v >= 1; v >>= 1) {
    uint32_t w = node_[v];
    if (w != i) {
      if (Winner(w, i) != i) return;
      node_[v] = i;
    }
  }
}

}  // namespace vismask
