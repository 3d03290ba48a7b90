#pragma once
// Constraints attached to Options fields (the third argument of `v(key, field, constraint,
// doc)` in an Options struct's visit(); see options.h). Each constraint checks a value and
// describes what it accepts, which is what error messages show after "expected":
//
//   any()                          everything of the field's type      "an integer"
//   in_range(1, 5000)              closed interval                     "an integer in [1, 5000]"
//   at_least(0.0), at_most(1.0)    one-sided closed bound              "a number >= 0"
//   greater_than(0.0), positive()  one-sided open bound                "a number > 0"
//   one_of({"a", "b"})             strings from a fixed set            "one of 'a', 'b'"
//   each_in_range(0.001, 10.0)     lists: a bound on every element     "a list of numbers, each in [0.001,
//   10]" list_size(1, 16)               lists: number of elements           "a list of 1 to 16 numbers"
//   each_in_range(a, b).size(1, 16) both
//   enum_names<Mode>({{"fast", Mode::kFast}, {"exact", Mode::kExact}})   enums read and written by name
//
// They live in the inline namespace mrvs::config::constraints, so code outside mrvs::config
// can write `using namespace mrvs::config::constraints;` inside its visit() functions.
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "mrvs/config/detail/codecs.h"

namespace mrvs::config {
inline namespace constraints {

/// Accepts every value of the field's type.
struct AnyValue {
  template <class T>
  bool accepts(const T& /*value*/) const {
    return true;
  }
  template <class T>
  std::string describe() const {
    return detail::Codec<T>::noun();
  }
};

/// Bounds on a number; B is the type the bounds were written in.
template <class B>
struct Range {
  static_assert(std::is_arithmetic_v<B> && !std::is_same_v<B, bool>, "range bounds must be numbers");
  std::optional<B> lo;
  std::optional<B> hi;
  bool lo_open = false;  ///< lo excluded
  bool hi_open = false;  ///< hi excluded

  template <class T>
  bool accepts(const T& value) const {
    static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>,
                  "in_range/at_least/at_most/greater_than apply to number fields only");
    using C = std::common_type_t<T, B>;
    const C x = static_cast<C>(value);
    if (lo && !(lo_open ? x > static_cast<C>(*lo) : x >= static_cast<C>(*lo))) return false;
    if (hi && !(hi_open ? x < static_cast<C>(*hi) : x <= static_cast<C>(*hi))) return false;
    return true;
  }
  /// "in [1, 5000]", "> 0", "<= 1".
  std::string bound_text() const {
    if (lo && hi) return fmt::format("in {}{}, {}{}", lo_open ? "(" : "[", *lo, *hi, hi_open ? ")" : "]");
    if (lo) return fmt::format("{} {}", lo_open ? ">" : ">=", *lo);
    if (hi) return fmt::format("{} {}", hi_open ? "<" : "<=", *hi);
    return "of any value";
  }
  template <class T>
  std::string describe() const {
    static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>,
                  "in_range/at_least/at_most/greater_than apply to number fields only");
    return detail::Codec<T>::noun() + " " + bound_text();
  }
};

/// A string from a fixed set.
struct OneOf {
  std::vector<std::string> names;

  template <class T>
  bool accepts(const T& value) const {
    static_assert(std::is_same_v<T, std::string>,
                  "one_of applies to std::string fields (use enum_names for enums)");
    for (const std::string& n : names) {
      if (n == value) return true;
    }
    return false;
  }
  std::string names_text() const {
    std::string out;
    for (const std::string& n : names) out += (out.empty() ? "'" : ", '") + n + "'";
    return out;
  }
  template <class T>
  std::string describe() const {
    return "one of " + names_text();
  }
};

/// Lists (std::vector, fixed-size Eigen vectors): element count and a bound on every element.
template <class B>
struct ListSpec {
  std::optional<Range<B>> each;
  std::size_t min_size = 0;
  std::size_t max_size = std::numeric_limits<std::size_t>::max();

  /// Same constraint, with between min and max elements (inclusive).
  ListSpec size(std::size_t min, std::size_t max) const {
    ListSpec copy = *this;
    copy.min_size = min;
    copy.max_size = max;
    return copy;
  }

  template <class T>
  bool accepts(const T& value) const {
    static_assert(detail::IsList<T>::value, "each_in_range/list_size apply to list fields only");
    const auto n = static_cast<std::size_t>(value.size());
    if (detail::Codec<T>::kFixedSize < 0 && (n < min_size || n > max_size)) return false;
    if (!each) return true;
    for (std::size_t i = 0; i < n; ++i) {
      if (!each->accepts(value[static_cast<decltype(value.size())>(i)])) return false;
    }
    return true;
  }
  template <class T>
  std::string describe() const {
    static_assert(detail::IsList<T>::value, "each_in_range/list_size apply to list fields only");
    using E = typename detail::Codec<T>::Element;
    std::string out = "a list of " + count_text(detail::Codec<T>::kFixedSize) + detail::Codec<E>::plural();
    if (each) out += ", each " + each->bound_text();
    return out;
  }

 private:
  std::string count_text(int fixed_size) const {
    constexpr std::size_t kNoMax = std::numeric_limits<std::size_t>::max();
    if (fixed_size >= 0) return fmt::format("{} ", fixed_size);
    if (min_size == max_size) return fmt::format("{} ", min_size);
    if (max_size == kNoMax) return min_size == 0 ? std::string() : fmt::format("{} or more ", min_size);
    if (min_size == 0) return fmt::format("up to {} ", max_size);
    return fmt::format("{} to {} ", min_size, max_size);
  }
};

/// An enum field read and written by name.
template <class E>
struct EnumNames {
  static_assert(std::is_enum_v<E>, "enum_names applies to enum fields");
  using Enum = E;
  std::vector<std::pair<std::string, E>> names;

  template <class T>
  bool accepts(const T& /*value*/) const {
    return true;  // decode() only produces listed values
  }
  template <class T>
  std::string describe() const {
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "'" : ", '") + n.first + "'";
    return "one of " + out;
  }
  bool decode(const YAML::Node& node, E& out) const {
    if (!node.IsScalar()) return false;
    for (const auto& n : names) {
      if (n.first == node.Scalar()) {
        out = n.second;
        return true;
      }
    }
    return false;
  }
  std::string encode(E value) const {
    for (const auto& n : names) {
      if (n.second == value) return detail::yaml_quote(n.first);
    }
    return fmt::format("\"<unnamed value {}>\"", static_cast<long long>(value));
  }
};

inline AnyValue any() { return {}; }

template <class A, class B>
Range<std::common_type_t<A, B>> in_range(A lo, B hi) {
  using C = std::common_type_t<A, B>;
  return Range<C>{static_cast<C>(lo), static_cast<C>(hi), false, false};
}
template <class B>
Range<B> at_least(B lo) {
  return Range<B>{lo, std::nullopt, false, false};
}
template <class B>
Range<B> at_most(B hi) {
  return Range<B>{std::nullopt, hi, false, false};
}
template <class B>
Range<B> greater_than(B lo) {
  return Range<B>{lo, std::nullopt, true, false};
}
/// > 0 (for ints and doubles alike).
inline Range<int> positive() { return greater_than(0); }

inline OneOf one_of(std::vector<std::string> names) { return OneOf{std::move(names)}; }

template <class A, class B>
ListSpec<std::common_type_t<A, B>> each_in_range(A lo, B hi) {
  ListSpec<std::common_type_t<A, B>> spec;
  spec.each = in_range(lo, hi);
  return spec;
}
/// Between min and max elements (inclusive), no bound on the values.
inline ListSpec<double> list_size(std::size_t min, std::size_t max) {
  return ListSpec<double>{}.size(min, max);
}

template <class E>
EnumNames<E> enum_names(std::vector<std::pair<std::string, E>> names) {
  return EnumNames<E>{std::move(names)};
}

}  // namespace constraints
}  // namespace mrvs::config
