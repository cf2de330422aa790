#pragma once

#include <memory>
#include <string>

namespace colorfree::sim {

/// An off-screen OpenGL context that MuJoCo's renderer can draw into. One backend now (OSMesa);
/// an EGL surfaceless backend can be added behind the same interface.
class GlContext {
 public:
  virtual ~GlContext() = default;
  /// Makes the context current on the calling thread (before any mjr_* call).
  virtual void makeCurrent() = 0;
  virtual std::string backendName() const = 0;

  /// Creates a context with a default framebuffer of the given size and makes it current.
  /// Throws colorfree::Error when no context can be made.
  static std::unique_ptr<GlContext> create(int width_px, int height_px);
};

}  // namespace colorfree::sim
