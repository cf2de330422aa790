// Compares two bench results.json files, leaving out only the wall-clock timing fields (per-stage
// times, CNN times per patch, wall time): exit 0 when equal, 1 naming the first difference.
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

namespace {

using json = nlohmann::json;

const std::set<std::string> kTimingKeys = {"timing_ms", "wall_s", "us_per_patch_single", "us_per_patch_batch16",
                                           "mean_ms", "max_ms"};

void dropTiming(json& j) {
  if (j.is_object()) {
    for (const auto& k : kTimingKeys) j.erase(k);
    for (auto& [k, v] : j.items()) dropTiming(v);
  } else if (j.is_array()) {
    for (auto& v : j) dropTiming(v);
  }
}

json load(const char* path) {
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "%s: cannot read\n", path);
    std::exit(2);
  }
  json j = json::parse(in);
  dropTiming(j);
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s A/results.json B/results.json\n", argv[0]);
    return 2;
  }
  const json a = load(argv[1]), b = load(argv[2]);
  if (a == b) {
    std::printf("equal except timing fields (%zu bytes compared)\n", a.dump().size());
    return 0;
  }
  const json patch = json::diff(a, b);
  std::printf("results differ (%zu differences), first: %s\n", patch.size(), patch.front().dump().substr(0, 400).c_str());
  return 1;
}
