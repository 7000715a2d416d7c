// Native-only headless rendering (not from the papers; library
// lk_render_native): an OSMesa context (core profile 3.3, which accepts the
// "#version 300 es" shaders) and a one-call render_offscreen() that returns
// an lk::Image (top row first; GL reads bottom-up, so rows are flipped).
#pragma once
#include "common/status.h"
#include "image/image.h"
#include "render/renderer.h"

#include <functional>
#include <memory>

namespace lk {

// Owns an OSMesa context and its RGBA color buffer. Only one can be current
// per thread; create() makes the new context current.
class OffscreenContext {
 public:
  OffscreenContext();
  ~OffscreenContext();
  OffscreenContext(const OffscreenContext&) = delete;
  OffscreenContext& operator=(const OffscreenContext&) = delete;

  // Sizes from 1 to 8192 pixels per side.
  Status create(int width, int height);
  Status make_current();
  int width() const;
  int height() const;
  // The current framebuffer as RGBA (4 channels), top row first.
  Status read_image(Image& out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct OffscreenOptions {
  int width = 512;      // output size in pixels
  int height = 512;
  int supersample = 2;  // renders at supersample x size and box-filters down (antialiasing), 1..4
  int channels = 3;     // 3 = RGB, 4 = RGBA (alpha = 255)
  RendererOptions renderer;
};

// Uploads the scene with `setup` (called on a fresh Renderer), draws it with
// camera_for(aspect) and returns the image. The whole GL state lives only
// during the call.
using SceneSetup = std::function<Status(Renderer& renderer)>;
using CameraForAspect = std::function<CameraMatrices(float aspect)>;
Status render_offscreen(const SceneSetup& setup, const CameraForAspect& camera_for,
                        const OffscreenOptions& options, Image& out);

}  // namespace lk
