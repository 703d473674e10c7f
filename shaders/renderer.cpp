#include "shaders/renderer.h"

#include <algorithm>
#include <cstring>

#include "core/error.h"
#include "kernels/buffers.h"
#include "kernels/runtime.h"
#include "shaders/codegen.h"

namespace proctex {
namespace {

// Largest output buffer of one launch; bounds device memory for huge renders and big batches.
constexpr size_t kMaxLaunchBytes = size_t(128) << 20;

cl::Kernel kernel_for(const ShaderDecl& decl) {
  auto& rt = ocl::Runtime::instance();
  cl::Program program = rt.program(generate_program(decl));
  return ocl::with_cl_errors("creating the render kernel", [&] { return cl::Kernel(program, kRenderKernelName); });
}

void check_settings(const RenderSettings& s) {
  check_dimensions(s.width, s.height);
  if (s.supersample < 1 || s.supersample > 16)
    throw UsageError("supersample must be in [1, 16], got " + std::to_string(s.supersample),
                     "use --supersample 1 to 4");
  if (!(s.extent > 0.0f)) throw UsageError("render extent must be positive", "use a positive --extent");
  if (!(s.filter >= 0.0f)) throw UsageError("filter scale must be >= 0", "use 1 for antialiasing, 0 for none");
}

}  // namespace

Renderer::Renderer(const ShaderLibrary& library) : library_(library) {}

void Renderer::prepare(const ShaderDecl& decl) { kernel_for(decl); }

Image Renderer::render(const TextureSpec& spec, const RenderSettings& settings) {
  const ShaderDecl& decl = library_.get(spec.shader);
  const std::vector<float> packed = resolve(decl, spec);
  return std::move(render_batch(decl, {packed}, {spec.seed}, settings).front());
}

std::vector<Image> Renderer::render_batch(const ShaderDecl& decl, const std::vector<std::vector<float>>& packed,
                                          const std::vector<uint32_t>& seeds, const RenderSettings& settings) {
  check_settings(settings);
  if (packed.size() != seeds.size()) throw Error("render_batch: one seed per parameter vector needed");
  for (const auto& v : packed)
    if (static_cast<int>(v.size()) != decl.packed_size)
      throw Error("render_batch: parameter vector of " + std::to_string(v.size()) + " floats for shader '" +
                  decl.name + "' which packs " + std::to_string(decl.packed_size));
  std::vector<Image> images;
  images.reserve(packed.size());
  for (size_t i = 0; i < packed.size(); ++i) images.emplace_back(settings.width, settings.height);
  if (packed.empty()) return images;

  cl::Kernel kernel = kernel_for(decl);
  const size_t stride = std::max(1, decl.packed_size);
  const size_t row_bytes = size_t(settings.width) * 3 * sizeof(float);
  const size_t image_bytes = row_bytes * settings.height;

  // Whole images per launch when they fit, else row tiles of a single image.
  const size_t samples_per_launch = std::clamp<size_t>(kMaxLaunchBytes / image_bytes, 1, packed.size());
  const int rows_per_launch =
      samples_per_launch > 1 ? settings.height
                             : static_cast<int>(std::clamp<size_t>(kMaxLaunchBytes / row_bytes, 1, settings.height));
  const float pixel = settings.extent / settings.height;

  for (size_t first = 0; first < packed.size(); first += samples_per_launch) {
    const size_t count = std::min(samples_per_launch, packed.size() - first);
    std::vector<float> params(count * stride, 0.0f);
    for (size_t i = 0; i < count; ++i) std::copy(packed[first + i].begin(), packed[first + i].end(), params.begin() + i * stride);
    const cl::Buffer params_buf = ocl::upload(params);
    const cl::Buffer seeds_buf = ocl::upload(seeds.data() + first, count);
    for (int y0 = 0; y0 < settings.height; y0 += rows_per_launch) {
      const int rows = std::min(rows_per_launch, settings.height - y0);
      const size_t floats_per_image = size_t(rows) * settings.width * 3;
      const cl::Buffer out = ocl::output_buffer(count * floats_per_image * sizeof(float));
      ocl::launch(kernel, cl::NDRange(settings.width, rows, count), params_buf, static_cast<cl_int>(stride), seeds_buf,
                  cl_float4{{settings.origin_u, settings.origin_v, pixel, settings.filter}}, static_cast<cl_int>(y0),
                  static_cast<cl_int>(settings.supersample), out);
      for (size_t i = 0; i < count; ++i)
        ocl::download_async(out, i * floats_per_image, floats_per_image, images[first + i].pixel(0, y0));
      ocl::finish();
      if (settings.on_progress)
        settings.on_progress((double(first) + double(count) * (y0 + rows) / settings.height) / packed.size());
    }
  }
  return images;
}

}  // namespace proctex
