#pragma once
// Frames of a texture transformation: what each frame renders, rendering them in batches, the
// quality measures of a sequence, and the animated GIF.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "image/image.h"
#include "metrics/metric.h"
#include "shaders/renderer.h"
#include "shaders/spec.h"

namespace proctex::transform {

struct Frame {
  TextureSpec spec;
  // Dissolve frames (--dissolve K at a jump) blend two renders: (1 - blend) spec + blend blend_to.
  std::optional<TextureSpec> blend_to;
  double blend = 0;
  int key = -1;            // index of the input this frame reproduces exactly, -1 otherwise
  bool jump = false;       // the step from the previous frame crosses a jump edge (or dissolves)
  double position = 0;     // perceptual position along the path, 0..1
  // Measured against the previous frame (NaN for the first frame or before measuring).
  double similarity = std::numeric_limits<double>::quiet_NaN();
  double layout = std::numeric_limits<double>::quiet_NaN();

  nlohmann::json to_json() const;
};

// Quality of a frame sequence: perceptual smoothness (adjacent dissimilarity 1 - S under the
// default metric) next to layout stability (mean absolute difference of adjacent frames, sRGB
// 0..1: noise that moves between frames flickers even when the frames are perceptually alike).
struct Quality {
  int frames = 0;
  double max_dissimilarity = 0, mean_dissimilarity = 0;
  int worst_step = -1;  // frame index whose step from the previous frame is the largest
  double layout_mean = 0, layout_max = 0;
  nlohmann::json to_json() const;
};

// Renders packed vectors of one shader at resolution x resolution and computes their default-metric
// features (jobs threads for the metric).
std::vector<metrics::Features> render_features(Renderer& renderer, const ShaderDecl& decl,
                                               const std::vector<std::vector<float>>& packed,
                                               const std::vector<uint32_t>& seeds, int resolution, int jobs);

// Renders frames [first, first + count) with `settings` (consecutive frames of one shader go in one
// launch; dissolve frames render both ends and blend).
std::vector<Image> render_frames(const std::vector<Frame>& frames, size_t first, size_t count, Renderer& renderer,
                                 const RenderSettings& settings);

// The perceptual length along a pixel cross-fade from the render of `a` to that of `b` at
// `resolution`: the cross-fade sampled at `samples` + 1 evenly spaced blend weights, element k the
// metric's distance -ln S summed from blend 0 to blend k / samples. A pixel cross-fade does not
// change the look evenly (the metric sees the first traces of a new texture most), so equal pixel
// weights make uneven steps; and its total length is what a dissolve costs.
std::vector<double> dissolve_curve(const TextureSpec& a, const TextureSpec& b, Renderer& renderer, int resolution,
                                   int jobs, int samples = 16);
// Blend weights (ascending, in (0, 1)) of `count` dissolve frames at equal perceptual distances
// along `curve` (linear within a sample interval).
std::vector<double> dissolve_blends(const std::vector<double>& curve, int count);

// Mean absolute difference of two equally sized images in sRGB [0, 1].
double layout_difference(const Image& a, const Image& b);

// Renders every frame at the analysis resolution, fills each frame's similarity and layout and
// returns the summary. `keep` (optional) receives each frame's render downsized to `keep_size`.
Quality measure(std::vector<Frame>& frames, Renderer& renderer, int resolution, int jobs,
                std::vector<Image>* keep = nullptr, int keep_size = 128,
                const std::function<void(double)>& progress = {});

// Animated GIF (image/io.h: OpenImageIO's GIF writer, one subimage per frame, looping).
void write_gif(const std::vector<Image>& frames, const std::filesystem::path& path, int fps);

}  // namespace proctex::transform
