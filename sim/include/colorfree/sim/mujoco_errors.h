#pragma once

namespace colorfree {

/// Replaces MuJoCo's default error handler (which prints and waits for Enter) with one that throws
/// colorfree::Error, and routes warnings to stderr. Idempotent; call before any MuJoCo use.
void installMujocoErrorHandlers();

}  // namespace colorfree
