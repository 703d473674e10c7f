#pragma once
// Renders shaders through OpenCL: many parameter vectors of one shader in one launch (what the
// catalogue and the search need), and single specs at any size (tiled, so memory stays bounded).
#include <cstdint>
#include <functional>
#include <vector>

#include "image/image.h"
#include "shaders/library.h"
#include "shaders/spec.h"

namespace proctex {

struct RenderSettings {
  int width = 256;
  int height = 256;
  int supersample = 1;     // samples per pixel along each axis (1 = analytic antialiasing only)
  float origin_u = 0.0f;   // texture coordinate of the top-left corner
  float origin_v = 0.0f;
  float extent = 1.0f;     // texture units spanned by the image height (width keeps square pixels)
  float filter = 1.0f;     // scales the footprint shaders filter over; 0 = point sampling (aliases)
  // Called after each launch with the fraction done (large renders go in several row tiles).
  std::function<void(double)> on_progress;
};

class Renderer {
 public:
  explicit Renderer(const ShaderLibrary& library = ShaderLibrary::builtin());

  // Validates the spec (unknown shader or parameter, out-of-range value: UsageError) and renders.
  Image render(const TextureSpec& spec, const RenderSettings& settings = {});

  // Renders packed parameter vectors (each decl.packed_size floats, already valid) with their
  // seeds; one image per vector. Splits into launches that keep device buffers bounded.
  std::vector<Image> render_batch(const ShaderDecl& decl, const std::vector<std::vector<float>>& packed,
                                  const std::vector<uint32_t>& seeds, const RenderSettings& settings = {});

  // Builds the shader's program now (otherwise the first render does); throws on compile errors.
  void prepare(const ShaderDecl& decl);

  const ShaderLibrary& library() const { return library_; }

 private:
  const ShaderLibrary& library_;
};

}  // namespace proctex
