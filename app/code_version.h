#pragma once
#include <string>

namespace colorfree {

/// What produced a result: the build's `git describe` and a fingerprint of the nets' weights the
/// run reads (perception/models is read at run time, so weights changed after the build show).
/// "0.1.0-687487a nets 1a2b3c4d", computed on the first call. Throws colorfree::Error when a shipped
/// weights file is missing.
std::string codeVersion();

}  // namespace colorfree
