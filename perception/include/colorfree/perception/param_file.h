#pragma once

#include <set>
#include <string>
#include <yaml-cpp/yaml.h>

#include "colorfree/perception/error.h"

namespace colorfree {

/// Reads one flat YAML parameter file strictly: every key read must be there with a value of the
/// right type, and `finish()` rejects keys that were never read. Errors name the file and the key.
class ParamFile {
 public:
  /// Loads `path`; throws colorfree::Error when the file is missing or not a YAML mapping.
  explicit ParamFile(const std::string& path);
  /// Wraps an already parsed mapping (e.g. a section of a larger file); `origin` names it in errors.
  ParamFile(YAML::Node node, std::string origin);

  template <typename T>
  T get(const std::string& key) {
    const YAML::Node value = node_[key];
    if (!value) throw Error(origin_ + ": missing key '" + key + "'");
    used_.insert(key);
    try {
      return value.as<T>();
    } catch (const YAML::Exception&) {
      throw Error(origin_ + ": key '" + key + "' has a value of the wrong type");
    }
  }

  /// Whether the file holds `key` (for optional keys; reading one is still a `get`).
  bool has(const std::string& key) const { return static_cast<bool>(node_[key]); }

  /// A number that must lie in [lo, hi]; NaN is rejected.
  double getInRange(const std::string& key, double lo, double hi);

  /// Throws when the file holds a key that no `get` asked for.
  void finish() const;

  const std::string& origin() const { return origin_; }

 private:
  YAML::Node node_;
  std::string origin_;
  std::set<std::string> used_;
};

/// The directory of the shipped parameter files (perception/params in the source tree).
std::string defaultParamDir();

}  // namespace colorfree
