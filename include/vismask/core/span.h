// Views over memory that vismask does not own (arena memory, fixed arrays).
// Span<T> is a pointer and a length; functions take spans, so they are not
// templated on a capacity.
#pragma once
#include <cstddef>

#include "vismask/core/check.h"

namespace vismask {

template <class T>
class Span {
 public:
  Span() = default;
  Span(T* data, size_t size) : data_(data), size_(size) {}
  template <class U>
  Span(const Span<U>& other) : data_(other.data()), size_(other.size()) {}

  T* data() const { return data_; }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  size_t bytes() const { return size_ * sizeof(T); }
  T& operator[](size_t i) const {
    DCHECK(i < size_);
    return data_[i];
  }
  T* begin() const { return data_; }
  T* end() const { return data_ + size_; }
  Span<T> subspan(size_t offset, size_t count) const {
    CHECK(offset + count <= size_);
    return Span<T>(data_ + offset, count);
  }

 private:
  T* data_ = nullptr;
  size_t size_ = 0;
};

}  // namespace vismask
