#pragma once

#include <stdexcept>
#include <string>

namespace colorfree {

/// The one error type of colorfree: bad input (a file, a value, an image), with a message that
/// names the file or value and what is wrong. Tools print it and exit non-zero.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace colorfree
