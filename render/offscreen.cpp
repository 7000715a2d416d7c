// Headless rendering with OSMesa (native only; see offscreen.h).
#include "render/offscreen.h"

#include "render/gl.h"

#include <GL/osmesa.h>

#include <string>
#include <vector>

namespace lk {

struct OffscreenContext::Impl {
  OSMesaContext context = nullptr;
  std::vector<std::uint8_t> buffer;  // RGBA, bottom row first (OSMesa's default)
  int width = 0, height = 0;
  ~Impl() {
    if (context) OSMesaDestroyContext(context);
  }
};

OffscreenContext::OffscreenContext() : impl_(std::make_unique<Impl>()) {}
OffscreenContext::~OffscreenContext() = default;
int OffscreenContext::width() const { return impl_->width; }
int OffscreenContext::height() const { return impl_->height; }

Status OffscreenContext::create(int width, int height) {
  constexpr int kMaxSide = 8192;
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    return Status::error(ErrorCode::InvalidInput, "offscreen size " + std::to_string(width) + "x" +
                                                      std::to_string(height) + " outside 1.." +
                                                      std::to_string(kMaxSide));
  if (impl_->context) {
    OSMesaDestroyContext(impl_->context);
    impl_->context = nullptr;
  }
  // A 3.3 core profile: Mesa then accepts "#version 300 es" shaders
  // (ARB_ES3_compatibility), so the WebGL2 shaders run unchanged.
  const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA,
                         OSMESA_DEPTH_BITS, 24,
                         OSMESA_STENCIL_BITS, 0,
                         OSMESA_ACCUM_BITS, 0,
                         OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                         OSMESA_CONTEXT_MAJOR_VERSION, 3,
                         OSMESA_CONTEXT_MINOR_VERSION, 3,
                         0};
  impl_->context = OSMesaCreateContextAttribs(attribs, nullptr);
  if (!impl_->context)
    return Status::error(ErrorCode::Unsupported, "OSMesa could not create a 3.3 core profile context");
  impl_->width = width;
  impl_->height = height;
  impl_->buffer.assign(static_cast<size_t>(width) * height * 4, 0);
  return make_current();
}

Status OffscreenContext::make_current() {
  if (!impl_->context) return Status::error(ErrorCode::InvalidInput, "offscreen context not created");
  if (!OSMesaMakeCurrent(impl_->context, impl_->buffer.data(), GL_UNSIGNED_BYTE, impl_->width,
                         impl_->height))
    return Status::error(ErrorCode::Internal, "OSMesaMakeCurrent failed");
  return Status::success();
}

Status OffscreenContext::read_image(Image& out) const {
  if (!impl_->context) return Status::error(ErrorCode::InvalidInput, "offscreen context not created");
  glFinish();
  const int w = impl_->width, h = impl_->height;
  out = Image::make(w, h, 4);
  const size_t row = static_cast<size_t>(w) * 4;
  for (int y = 0; y < h; ++y)
    std::copy_n(&impl_->buffer[static_cast<size_t>(h - 1 - y) * row], row, out.at(0, y));
  return Status::success();
}

namespace {

// Box filter by an integer factor; keeps the first `channels` of RGBA.
Image downsample(const Image& big, int factor, int channels) {
  const int w = big.width / factor, h = big.height / factor;
  Image out = Image::make(w, h, channels);
  const int n = factor * factor;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      int sum[4] = {0, 0, 0, 0};
      for (int dy = 0; dy < factor; ++dy)
        for (int dx = 0; dx < factor; ++dx) {
          const std::uint8_t* p = big.at(x * factor + dx, y * factor + dy);
          for (int c = 0; c < 4; ++c) sum[c] += p[c];
        }
      std::uint8_t* q = out.at(x, y);
      for (int c = 0; c < channels; ++c) q[c] = static_cast<std::uint8_t>((sum[c] + n / 2) / n);
    }
  return out;
}

}  // namespace

Status render_offscreen(const SceneSetup& setup, const CameraForAspect& camera_for,
                        const OffscreenOptions& options, Image& out) {
  if (options.supersample < 1 || options.supersample > 4)
    return Status::error(ErrorCode::InvalidInput, "supersample must be 1..4");
  if (options.channels != 3 && options.channels != 4)
    return Status::error(ErrorCode::InvalidInput, "channels must be 3 or 4");
  if (options.width < 1 || options.height < 1)
    return Status::error(ErrorCode::InvalidInput, "image size must be positive");
  const int ss = options.supersample;
  OffscreenContext context;
  Status s = context.create(options.width * ss, options.height * ss);
  if (!s) return s;
  Image big;
  {
    Renderer renderer;  // destroyed before the context
    s = renderer.init(options.renderer);
    if (!s) return s;
    if (setup) {
      s = setup(renderer);
      if (!s) return s;
    }
    const float aspect = static_cast<float>(options.width) / static_cast<float>(options.height);
    const CameraMatrices camera = camera_for ? camera_for(aspect) : CameraMatrices{};
    s = renderer.draw(camera, Viewport{0, 0, context.width(), context.height()});
    if (!s) return s;
    s = context.read_image(big);
    if (!s) return s;
  }
  out = downsample(big, ss, options.channels);
  return Status::success();
}

}  // namespace lk
