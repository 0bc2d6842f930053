// Arena: the one block of memory an environment (or a rank's output stage)
// owns. Everything is carved from it at init by bump allocation; nothing is
// freed until the arena dies. Overflow is a bug (CHECK), because the arena is
// sized exactly from the scene before it is made: run the same layout code
// once against a measuring arena (Arena::Measure()), which hands out no memory
// but counts bytes, then make the real arena with Measured() bytes and run the
// layout again. Copying is deleted; moving is allowed.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <new>
#include <type_traits>

#include "vismask/core/span.h"

namespace vismask {

class Arena {
 public:
  static constexpr size_t kAlign = 64;  // cache line

  // A measuring arena: Alloc returns spans with null data and counts bytes.
  static Arena Measure() { return Arena(); }
  // A real arena of `capacity` bytes, one aligned heap block (init only).
  // The system's refusal is a CHECK failure: user-sized arenas use Reserve.
  explicit Arena(size_t capacity);
  // Makes *out a real arena of `capacity` bytes; false, leaving *out as it
  // was, if the system refuses the memory (the caller says so, exit 2).
  static bool Reserve(size_t capacity, Arena* out);
  ~Arena();
  Arena(Arena&& other) noexcept;
  Arena& operator=(Arena&& other) noexcept;
  Arena(const Arena&) = delete;
  Arena& operator=(const Arena&) = delete;

  bool measuring() const { return base_ == nullptr; }
  size_t used() const { return used_; }
  size_t capacity() const { return capacity_; }
  size_t remaining() const { return capacity_ - used_; }
  // The bytes handed out so far (used() of them; null while measuring):
  // what a checkpoint saves and restores (checkpoint.h).
  uint8_t* data() { return base_; }
  const uint8_t* data() const { return base_; }

  // `bytes` bytes aligned to `align` (a power of two <= kAlign). Zeroed.
  // Zero bytes reserve nothing (null).
  void* AllocBytes(size_t bytes, size_t align);

  // `n` value-initialised T. T must be trivially destructible: the arena never
  // runs destructors.
  template <class T>
  Span<T> Alloc(size_t n) {
    static_assert(std::is_trivially_destructible<T>::value, "arena types are never destroyed");
    void* p = AllocBytes(n * sizeof(T), alignof(T) < 16 ? 16 : alignof(T));
    if (!p) return Span<T>(nullptr, n);
    T* t = static_cast<T*>(p);
    for (size_t i = 0; i < n; ++i) new (t + i) T();
    return Span<T>(t, n);
  }

 private:
  Arena() = default;
  uint8_t* base_ = nullptr;
  size_t capacity_ = 0;
  size_t used_ = 0;
};

// Rounds `n` up to a multiple of Arena::kAlign: the size to ask for so that a
// measured layout fits a real arena whose base is kAlign-aligned.
inline size_t ArenaRoundUp(size_t n) {
  return (n + Arena::kAlign - 1) & ~(Arena::kAlign - 1);
}

}  // namespace vismask
