#include "gl_context.h"

#include <GL/osmesa.h>

#include <cstdint>
#include <vector>

#include "colorfree/perception/error.h"

namespace colorfree::sim {

namespace {

// OSMesa: software rendering, no display. MuJoCo renders into its own off-screen framebuffer
// object; this buffer only backs the default framebuffer the context needs to be current.
class OsMesaContext : public GlContext {
 public:
  OsMesaContext(int width_px, int height_px)
      : width_(width_px),
        height_(height_px),
        buffer_(static_cast<std::size_t>(width_px) * height_px * 4) {
    context_ = OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
    if (context_ == nullptr) throw Error("OSMesa: cannot create an off-screen GL context");
    makeCurrent();
  }
  ~OsMesaContext() override { OSMesaDestroyContext(context_); }
  OsMesaContext(const OsMesaContext&) = delete;
  OsMesaContext& operator=(const OsMesaContext&) = delete;

  void makeCurrent() override {
    if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, width_, height_)) {
      throw Error("OSMesa: cannot make the off-screen GL context current");
    }
  }
  std::string backendName() const override { return "osmesa"; }

 private:
  OSMesaContext context_ = nullptr;
  int width_;
  int height_;
  std::vector<std::uint8_t> buffer_;
};

}  // namespace

std::unique_ptr<GlContext> GlContext::create(int width_px, int height_px) {
  if (width_px <= 0 || height_px <= 0) {
    throw Error("GL context: impossible buffer size " + std::to_string(width_px) + "x" +
                std::to_string(height_px));
  }
  return std::make_unique<OsMesaContext>(width_px, height_px);
}

}  // namespace colorfree::sim
