#pragma once
// A member most records leave empty, held on the heap only when set: a pointer's
// eight bytes instead of the value's own (a Mesh is 144 bytes of empty arrays),
// for the two million nodes of a million-fragment tree, most of them convex and
// so without a hull of their own.

#include <memory>
#include <utility>

namespace shatter {

/// A value of T with value semantics (copies are deep), held on the heap once
/// set and absent until then. An absent value reads as T{}. Reading it through
/// a non-const Boxed makes it present (as T{}), since the caller may write it.
template <class T>
class Boxed {
 public:
  Boxed() = default;
  Boxed(T value) : value_(std::make_unique<T>(std::move(value))) {}  // NOLINT: converts as T's own member did
  Boxed(const Boxed& other) : value_(other.value_ ? std::make_unique<T>(*other.value_) : nullptr) {}
  Boxed(Boxed&&) noexcept = default;
  Boxed& operator=(const Boxed& other) {
    if (this != &other) value_ = other.value_ ? std::make_unique<T>(*other.value_) : nullptr;
    return *this;
  }
  Boxed& operator=(Boxed&&) noexcept = default;
  Boxed& operator=(T value) {
    value_ = std::make_unique<T>(std::move(value));
    return *this;
  }
  ~Boxed() = default;

  const T& operator*() const { return value_ ? *value_ : absent(); }
  const T* operator->() const { return &**this; }
  T& operator*() {
    if (!value_) value_ = std::make_unique<T>();
    return *value_;
  }
  T* operator->() { return &**this; }
  operator const T&() const { return **this; }  // NOLINT: reads as a const T&

  /// Whether a value was set (or read through a non-const Boxed).
  bool present() const { return value_ != nullptr; }
  /// Frees the value: absent again.
  void reset() { value_.reset(); }

 private:
  static const T& absent() {
    static const T empty{};
    return empty;
  }
  std::unique_ptr<T> value_;
};

}  // namespace shatter
