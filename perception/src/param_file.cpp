#include "colorfree/perception/param_file.h"

#include <cmath>
#include <sstream>

namespace colorfree {

ParamFile::ParamFile(const std::string& path) : origin_(path) {
  try {
    node_ = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw Error(path + ": cannot open parameter file");
  } catch (const YAML::ParserException& e) {
    throw Error(path + ": line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!node_.IsMap()) throw Error(path + ": expected a mapping of key: value");
}

ParamFile::ParamFile(YAML::Node node, std::string origin)
    : node_(std::move(node)), origin_(std::move(origin)) {
  if (!node_.IsMap()) throw Error(origin_ + ": expected a mapping of key: value");
}

double ParamFile::getInRange(const std::string& key, double lo, double hi) {
  const double v = get<double>(key);
  if (!std::isfinite(v) || v < lo || v > hi) {
    std::ostringstream msg;
    msg << origin_ << ": key '" << key << "' = " << v << " is outside [" << lo << ", " << hi << "]";
    throw Error(msg.str());
  }
  return v;
}

void ParamFile::finish() const {
  for (const auto& kv : node_) {
    const std::string key = kv.first.as<std::string>();
    if (!used_.count(key)) throw Error(origin_ + ": unknown key '" + key + "'");
  }
}

std::string defaultParamDir() { return std::string(COLORFREE_SOURCE_DIR) + "/perception/params"; }

}  // namespace colorfree
