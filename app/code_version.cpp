#include "code_version.h"

#include <cstdio>
#include <fstream>
#include <iterator>

#include "bench_plan.h"
#include "colorfree/perception/cnn/shipped_nets.h"
#include "colorfree/perception/error.h"
#include "colorfree_git_version.h"

namespace colorfree {

namespace {

std::string computeCodeVersion() {
  std::uint64_t hash = app::fnv1a("");  // over every net's name and weights bytes
  for (const cnn::ShippedNet& net : cnn::kShippedNets) {
    std::ifstream in(net.weightsPath(), std::ios::binary);
    if (!in) throw Error(net.weightsPath() + ": cannot read the weights file");
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    hash = app::fnv1a(bytes, app::fnv1a(net.stem, hash));
  }
  char fingerprint[16];
  std::snprintf(fingerprint, sizeof fingerprint, "%08x", static_cast<unsigned>(hash ^ (hash >> 32)));
  return std::string(COLORFREE_GIT_DESCRIBE) + " nets " + fingerprint;
}

}  // namespace

std::string codeVersion() {
  static const std::string version = computeCodeVersion();  // the weights a run reads, read once
  return version;
}

}  // namespace colorfree
