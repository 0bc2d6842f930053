#include "vismask/core/arena.h"

#include <cstdlib>
#include <utility>

namespace vismask {

Arena::Arena(size_t capacity) : capacity_(ArenaRoundUp(capacity)) {
  if (capacity_ == 0) capacity_ = kAlign;
  base_ = static_cast<uint8_t*>(std::aligned_alloc(kAlign, capacity_));
  CHECK_MSG(base_ != nullptr, "arena allocation failed");
  std::memset(base_, 0, capacity_);
}

bool Arena::Reserve(size_t capacity, Arena* out) {
  Arena a;
  a.capacity_ = ArenaRoundUp(capacity);
  if (a.capacity_ == 0) a.capacity_ = kAlign;
  a.base_ = static_cast<uint8_t*>(std::aligned_alloc(kAlign, a.capacity_));
  if (a.base_ == nullptr) {
    a.capacity_ = 0;
    return false;
  }
  std::memset(a.base_, 0, a.capacity_);
  *out = std::move(a);
  return true;
}

Arena::~Arena() {
  std::free(base_);
}

Arena::Arena(Arena&& o) noexcept : base_(o.base_), capacity_(o.capacity_), used_(o.used_) {
  o.base_ = nullptr;
  o.capacity_ = o.used_ = 0;
}

Arena& Arena::operator=(Arena&& o) noexcept {
  if (this != &o) {
    std::free(base_);
    base_ = std::exchange(o.base_, nullptr);
    capacity_ = std::exchange(o.capacity_, 0);
    used_ = std::exchange(o.used_, 0);
  }
  return *this;
}

void* Arena::AllocBytes(size_t bytes, size_t align) {
  CHECK(align != 0 && (align & (align - 1)) == 0 && align <= kAlign);
  if (bytes == 0) return nullptr;  // nothing reserved, not even alignment padding
  size_t start = (used_ + align - 1) & ~(align - 1);
  if (measuring()) {
    used_ = start + bytes;
    return nullptr;
  }
  CHECK_MSG(start + bytes <= capacity_, "arena overflow: the init-time layout was not measured");
  used_ = start + bytes;
  return base_ + start;  // zeroed at construction, never reused
}

}  // namespace vismask
