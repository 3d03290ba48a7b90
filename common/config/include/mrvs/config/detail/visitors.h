#pragma once
// Implementation detail of options.h: the visitors that an Options struct's visit() is run
// with. Each one walks the same `v(key, field, constraint, doc)` / `v.section(key, sub)`
// calls, which is why loading, printing, saving and comparing cannot drift apart.
#include <cstddef>
#include <filesystem>
#include <string>
#include <type_traits>
#include <typeinfo>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "mrvs/config/constraints.h"
#include "mrvs/config/detail/codecs.h"
#include "mrvs/config/yaml_document.h"

namespace mrvs::config::detail {

template <class C>
struct IsEnumNames : std::false_type {};
template <class E>
struct IsEnumNames<EnumNames<E>> : std::true_type {};

template <class T, class C>
void check_field_types() {
  if constexpr (IsEnumNames<C>::value) {
    static_assert(std::is_same_v<T, typename C::Enum>, "enum_names<E> must be used with a field of type E");
  } else {
    static_assert(
        Codec<T>::kSupported,
        "unsupported Options field type (see mrvs/config/detail/codecs.h; use enum_names for enums)");
  }
}

template <class T, class C>
bool decode_value(const YAML::Node& node, T& out, const C& constraint) {
  if constexpr (IsEnumNames<C>::value) {
    return constraint.decode(node, out);
  } else {
    return Codec<T>::decode(node, out);
  }
}

template <class T, class C>
std::string encode_value(const T& value, const C& constraint) {
  if constexpr (IsEnumNames<C>::value) {
    return constraint.encode(value);
  } else {
    return Codec<T>::encode(value);
  }
}

template <class T>
bool values_equal(const T& a, const T& b) {
  if constexpr (std::is_enum_v<T>) {
    return a == b;
  } else {
    return Codec<T>::equal(a, b);
  }
}

/// Walks an Options struct and records the address and type of every field, in visit
/// order, so a second walk over another instance can pair its fields with these.
class FieldAddresses {
 public:
  template <class T, class C>
  void operator()(const char* /*key*/, T& field, const C& /*constraint*/, const char* /*doc*/ = "") {
    fields_.push_back({&field, &typeid(T)});
  }
  template <class S>
  void section(const char* /*key*/, S& sub, const char* /*doc*/ = "") {
    sub.visit(*this);
  }
  /// The i-th field if it has type T, else nullptr (a visit() whose calls depend on the
  /// field values breaks the pairing; it is then reported as a difference, not UB).
  template <class T>
  const T* get(std::size_t i) const {
    if (i >= fields_.size() || *fields_[i].type != typeid(T)) return nullptr;
    return static_cast<const T*>(fields_[i].address);
  }

 private:
  struct Entry {
    const void* address;
    const std::type_info* type;
  };
  std::vector<Entry> fields_;
};

/// Builds "a.b.c" key paths while walking nested sections.
class KeyPath {
 public:
  explicit KeyPath(std::string prefix) : prefix_(std::move(prefix)) {}
  std::string join(const char* key) const { return prefix_.empty() ? std::string(key) : prefix_ + "." + key; }
  const std::string& prefix() const { return prefix_; }

 private:
  std::string prefix_;
};

/// Reads one section of a YamlDocument into an Options struct, collecting every error.
class Loader {
 public:
  /// `map` is the section's node (undefined or null when the section is absent).
  Loader(const YamlDocument& doc, YAML::Node map, std::string prefix, std::vector<std::string>* errors)
      : doc_(doc), map_(std::move(map)), path_(std::move(prefix)), errors_(errors) {}

  template <class T, class C>
  void operator()(const char* key, T& field, const C& constraint, const char* /*doc*/ = "") {
    check_field_types<T, C>();
    known_.emplace_back(key);
    const YAML::Node node = find(key);
    if (!node.IsDefined()) return;  // absent: keep the default
    const std::string dotted = path_.join(key);
    T value = field;
    if (!decode_value(node, value, constraint) || !constraint.template accepts<T>(value)) {
      errors_->push_back(expected_error(doc_, node, dotted, constraint.template describe<T>()));
      return;
    }
    if constexpr (std::is_same_v<T, std::filesystem::path>) {
      if (doc_.overrides.count(dotted) == 0) value = resolve_path(doc_, value);
    }
    field = std::move(value);
  }

  template <class S>
  void section(const char* key, S& sub, const char* /*doc*/ = "") {
    known_.emplace_back(key);
    const YAML::Node node = find(key);
    if (node.IsDefined() && !node.IsNull() && !node.IsMap()) {
      errors_->push_back(expected_error(doc_, node, path_.join(key), "a section (a map of keys)"));
      return;
    }
    Loader child(doc_, node, path_.join(key), errors_);
    sub.visit(child);
    child.finish();
  }

  /// Reports keys of the section that no field claimed (with a "did you mean" hint) and
  /// duplicated keys. Call after visit().
  void finish() const;

 private:
  /// The value node of `key`, or an undefined node.
  YAML::Node find(const char* key) const;

  const YamlDocument& doc_;
  YAML::Node map_;
  KeyPath path_;
  std::vector<std::string>* errors_;
  std::vector<std::string> known_;
};

/// Checks the current values of a struct against its constraints (no file involved).
class Validator {
 public:
  Validator(std::string prefix, std::vector<std::string>* errors)
      : path_(std::move(prefix)), errors_(errors) {}

  template <class T, class C>
  void operator()(const char* key, T& field, const C& constraint, const char* /*doc*/ = "") {
    check_field_types<T, C>();
    if (!constraint.template accepts<T>(field)) {
      errors_->push_back(fmt::format("key '{}': expected {}, got '{}'", path_.join(key),
                                     constraint.template describe<T>(), encode_value(field, constraint)));
    }
  }
  template <class S>
  void section(const char* key, S& sub, const char* /*doc*/ = "") {
    Validator child(path_.join(key), errors_);
    sub.visit(child);
  }

 private:
  KeyPath path_;
  std::vector<std::string>* errors_;
};

/// One output line of the YAML writer.
struct YamlLine {
  int depth = 0;
  std::string key;
  std::string value;    ///< empty for a section header
  std::string comment;  ///< without '#'
};

/// Renders lines as YAML (two spaces per level), comments aligned in one column.
std::string render_yaml_lines(const std::vector<YamlLine>& lines);

/// Writes the fields of a struct as YAML lines; marks fields equal to the paired default.
class Writer {
 public:
  Writer(const FieldAddresses& defaults, int depth, bool comments, bool mark_defaults)
      : defaults_(defaults), depth_(depth), comments_(comments), mark_defaults_(mark_defaults) {}

  template <class T, class C>
  void operator()(const char* key, T& field, const C& constraint, const char* doc = "") {
    check_field_types<T, C>();
    const T* def = defaults_.get<T>(index_++);
    const bool is_default = def != nullptr && values_equal(field, *def);
    std::string comment = comments_ ? std::string(doc) : std::string();
    if (mark_defaults_ && is_default) comment += comment.empty() ? "(default)" : " (default)";
    lines_.push_back({depth_, key, encode_value(field, constraint), std::move(comment)});
  }
  template <class S>
  void section(const char* key, S& sub, const char* doc = "") {
    lines_.push_back({depth_, key, "", comments_ ? std::string(doc) : std::string()});
    ++depth_;
    sub.visit(*this);
    --depth_;
  }
  std::vector<YamlLine>& lines() { return lines_; }

 private:
  const FieldAddresses& defaults_;
  std::size_t index_ = 0;
  int depth_;
  bool comments_;
  bool mark_defaults_;
  std::vector<YamlLine> lines_;
};

/// Lists the dotted keys whose values differ from the paired struct.
class Differ {
 public:
  Differ(const FieldAddresses& other, std::vector<std::string>* differences)
      : other_(other), path_(""), differences_(differences) {}

  template <class T, class C>
  void operator()(const char* key, T& field, const C& /*constraint*/, const char* /*doc*/ = "") {
    const T* other = other_.get<T>(index_++);
    if (other == nullptr || !values_equal(field, *other)) differences_->push_back(path_.join(key));
  }
  template <class S>
  void section(const char* key, S& sub, const char* /*doc*/ = "") {
    KeyPath saved = path_;
    path_ = KeyPath(path_.join(key));
    sub.visit(*this);
    path_ = saved;
  }

 private:
  const FieldAddresses& other_;
  std::size_t index_ = 0;
  KeyPath path_;
  std::vector<std::string>* differences_;
};

/// Joins error lines into one InvalidArgument status (OK when there are none).
Status errors_to_status(const std::vector<std::string>& errors);

}  // namespace mrvs::config::detail
