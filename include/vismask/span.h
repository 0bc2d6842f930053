// Views over memory that vismask does not own (arena memory, fixed arrays).
// Span<T> is a pointer and a length. FixedVec<T> is a Span with a size: it
// fills up to its capacity and never grows; pushing past capacity is a bug
// (CHECK), so callers size it at init. Functions take these views, so they
// are not templated on a capacity (the ETL ivector idea).
#pragma once
#include <cstddef>

#include "vismask/check.h"

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

template <class T>
class FixedVec {
 public:
  FixedVec() = default;
  explicit FixedVec(Span<T> storage) : storage_(storage) {}

  size_t size() const { return size_; }
  size_t capacity() const { return storage_.size(); }
  bool full() const { return size_ == storage_.size(); }
  void clear() { size_ = 0; }
  void push_back(const T& v) {
    CHECK_MSG(size_ < storage_.size(), "FixedVec capacity exceeded");
    storage_[size_++] = v;
  }
  T& operator[](size_t i) const {
    DCHECK(i < size_);
    return storage_[i];
  }
  T* begin() const { return storage_.data(); }
  T* end() const { return storage_.data() + size_; }
  Span<T> view() const { return Span<T>(storage_.data(), size_); }

 private:
  Span<T> storage_;
  size_t size_ = 0;
};

}  // namespace vismask
