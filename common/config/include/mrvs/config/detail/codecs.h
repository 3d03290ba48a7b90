#pragma once
// Implementation detail of options.h: how each supported field type is read from a YAML
// node, written back as YAML text, compared, and described in error messages.
//
// Supported: bool, every integer type, float, double, std::string, std::filesystem::path,
// std::vector of those scalars, and fixed-size Eigen column vectors (Eigen::Matrix<S, N, 1>).
// Enums go through an EnumNames constraint (see options.h) instead of a codec.
#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <system_error>
#include <type_traits>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

namespace mrvs::config::detail {

/// Parses a YAML float ("1.5", "-2e-3", ".inf", "-.inf", ".nan"); false on anything else.
bool parse_double(const std::string& text, double* out);
/// Parses a YAML boolean (true/false, yes/no, on/off in any case); false on anything else.
bool parse_bool(const std::string& text, bool* out);
/// Shortest text that reads back to the same double, always with a '.' or an exponent
/// ("10.0", "0.001", "1e-05", ".inf", ".nan").
std::string format_double(double value);
/// The same for float.
std::string format_float(float value);
/// A string as a YAML scalar: plain when that reads back unchanged, else double-quoted.
std::string yaml_quote(const std::string& text);

template <class T, class Enable = void>
struct Codec {
  static constexpr bool kSupported = false;
};

template <>
struct Codec<bool> {
  static constexpr bool kSupported = true;
  static std::string noun() { return "a boolean (true/false)"; }
  static std::string plural() { return "booleans"; }
  static bool decode(const YAML::Node& node, bool& out) {
    return node.IsScalar() && parse_bool(node.Scalar(), &out);
  }
  static std::string encode(bool value) { return value ? "true" : "false"; }
  static bool equal(bool a, bool b) { return a == b; }
};

template <class T>
struct Codec<T, std::enable_if_t<std::is_integral_v<T> && !std::is_same_v<T, bool>>> {
  static constexpr bool kSupported = true;
  static std::string noun() { return std::is_signed_v<T> ? "an integer" : "a non-negative integer"; }
  static std::string plural() { return std::is_signed_v<T> ? "integers" : "non-negative integers"; }
  static bool decode(const YAML::Node& node, T& out) {
    if (!node.IsScalar()) return false;
    const std::string& s = node.Scalar();
    const char* first = s.data();
    const char* last = s.data() + s.size();
    if (first != last && *first == '+') ++first;
    T value{};
    const auto [ptr, ec] = std::from_chars(first, last, value, 10);
    if (ec != std::errc() || ptr != last || first == last) return false;
    out = value;
    return true;
  }
  static std::string encode(T value) { return fmt::format("{}", value); }
  static bool equal(T a, T b) { return a == b; }
};

template <class T>
struct Codec<T, std::enable_if_t<std::is_floating_point_v<T>>> {
  static constexpr bool kSupported = true;
  static std::string noun() { return "a number"; }
  static std::string plural() { return "numbers"; }
  static bool decode(const YAML::Node& node, T& out) {
    double value = 0.0;
    if (!node.IsScalar() || !parse_double(node.Scalar(), &value)) return false;
    if (std::isfinite(value) && std::abs(value) > static_cast<double>(std::numeric_limits<T>::max()))
      return false;
    out = static_cast<T>(value);
    return true;
  }
  static std::string encode(T value) {
    if constexpr (std::is_same_v<T, float>) return format_float(value);
    return format_double(static_cast<double>(value));
  }
  static bool equal(T a, T b) { return a == b || (std::isnan(a) && std::isnan(b)); }
};

template <>
struct Codec<std::string> {
  static constexpr bool kSupported = true;
  static std::string noun() { return "a string"; }
  static std::string plural() { return "strings"; }
  static bool decode(const YAML::Node& node, std::string& out) {
    if (!node.IsScalar()) return false;
    out = node.Scalar();
    return true;
  }
  static std::string encode(const std::string& value) { return yaml_quote(value); }
  static bool equal(const std::string& a, const std::string& b) { return a == b; }
};

/// Paths: relative paths read from a file are resolved against that file's folder (the
/// loader does that; see resolve_path in yaml_document.h).
template <>
struct Codec<std::filesystem::path> {
  static constexpr bool kSupported = true;
  static std::string noun() { return "a path"; }
  static std::string plural() { return "paths"; }
  static bool decode(const YAML::Node& node, std::filesystem::path& out) {
    if (!node.IsScalar()) return false;
    out = node.Scalar();
    return true;
  }
  static std::string encode(const std::filesystem::path& value) { return yaml_quote(value.string()); }
  static bool equal(const std::filesystem::path& a, const std::filesystem::path& b) { return a == b; }
};

/// Shared code of the list codecs (std::vector and fixed-size Eigen vectors).
template <class E>
struct ListCodecBase {
  using Element = E;
  static std::string encode_range(const E* data, std::size_t n) {
    std::string out = "[";
    for (std::size_t i = 0; i < n; ++i) out += (i == 0 ? "" : ", ") + Codec<E>::encode(data[i]);
    return out + "]";
  }
  template <class Out>
  static bool decode_into(const YAML::Node& node, Out* out) {
    if (!node.IsSequence()) return false;
    for (std::size_t i = 0; i < node.size(); ++i) {
      E value{};
      if (!Codec<E>::decode(node[i], value)) return false;
      out->push_back(value);
    }
    return true;
  }
};

template <class E>
struct Codec<std::vector<E>, std::enable_if_t<Codec<E>::kSupported && !std::is_same_v<E, bool>>>
    : ListCodecBase<E> {
  static constexpr bool kSupported = true;
  static constexpr int kFixedSize = -1;
  static std::string noun() { return "a list of " + Codec<E>::plural(); }
  static bool decode(const YAML::Node& node, std::vector<E>& out) {
    std::vector<E> values;
    if (!ListCodecBase<E>::decode_into(node, &values)) return false;
    out = std::move(values);
    return true;
  }
  static std::string encode(const std::vector<E>& value) {
    return ListCodecBase<E>::encode_range(value.data(), value.size());
  }
  static bool equal(const std::vector<E>& a, const std::vector<E>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (!Codec<E>::equal(a[i], b[i])) return false;
    }
    return true;
  }
};

template <class S, int N>
struct Codec<Eigen::Matrix<S, N, 1>, std::enable_if_t<(N > 0) && std::is_arithmetic_v<S>>>
    : ListCodecBase<S> {
  using Vector = Eigen::Matrix<S, N, 1>;
  static constexpr bool kSupported = true;
  static constexpr int kFixedSize = N;
  static std::string noun() { return fmt::format("a list of {} {}", N, Codec<S>::plural()); }
  static bool decode(const YAML::Node& node, Vector& out) {
    std::vector<S> values;
    if (!ListCodecBase<S>::decode_into(node, &values) || values.size() != static_cast<std::size_t>(N))
      return false;
    for (int i = 0; i < N; ++i) out[i] = values[static_cast<std::size_t>(i)];
    return true;
  }
  static std::string encode(const Vector& value) {
    return ListCodecBase<S>::encode_range(value.data(), static_cast<std::size_t>(N));
  }
  static bool equal(const Vector& a, const Vector& b) {
    for (int i = 0; i < N; ++i) {
      if (!Codec<S>::equal(a[i], b[i])) return false;
    }
    return true;
  }
};

/// True for the list types (they have an Element type).
template <class T, class = void>
struct IsList : std::false_type {};
template <class T>
struct IsList<T, std::void_t<typename Codec<T>::Element>> : std::true_type {};

}  // namespace mrvs::config::detail
