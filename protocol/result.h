#pragma once
// A small expected-like type: C++20 has no std::expected, and decode errors must reach the
// caller as values, never as exceptions thrown through it.
#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace omega::protocol {

template <class E>
struct Failure {
  E code;
  std::string message;
};

template <class E>
Failure<E> fail(E code, std::string message) {
  return Failure<E>{code, std::move(message)};
}

template <class T, class E>
class Result {
 public:
  Result(T value) : v_(std::in_place_index<0>, std::move(value)) {}  // NOLINT: implicit on purpose
  Result(Failure<E> f) : v_(std::in_place_index<1>, std::move(f)) {}  // NOLINT

  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }

  T& value() & { assert(ok()); return std::get<0>(v_); }
  const T& value() const& { assert(ok()); return std::get<0>(v_); }
  T&& value() && { assert(ok()); return std::get<0>(std::move(v_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

  const Failure<E>& error() const { assert(!ok()); return std::get<1>(v_); }
  E code() const { return error().code; }
  const std::string& message() const { return error().message; }

 private:
  std::variant<T, Failure<E>> v_;
};

}  // namespace omega::protocol
