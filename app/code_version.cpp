#include "code_version.h"

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>

#include "colorfree/perception/cnn/shipped_nets.h"
#include "colorfree/perception/error.h"
#include "colorfree_git_version.h"

namespace colorfree {

std::string codeVersion() {
  std::uint64_t hash = 0xcbf29ce484222325ULL;  // FNV-1a over every net's name and weights bytes
  const auto mix = [&hash](unsigned char c) {
    hash ^= c;
    hash *= 0x100000001b3ULL;
  };
  for (const cnn::ShippedNet& net : cnn::kShippedNets) {
    for (const char* c = net.stem; *c != '\0'; ++c) mix(static_cast<unsigned char>(*c));
    std::ifstream in(net.weightsPath(), std::ios::binary);
    if (!in) throw Error(net.weightsPath() + ": cannot read the weights file");
    for (std::istreambuf_iterator<char> it(in), end; it != end; ++it) mix(static_cast<unsigned char>(*it));
  }
  char fingerprint[16];
  std::snprintf(fingerprint, sizeof fingerprint, "%08x", static_cast<unsigned>(hash ^ (hash >> 32)));
  return std::string(COLORFREE_GIT_DESCRIBE) + " nets " + fingerprint;
}

}  // namespace colorfree
