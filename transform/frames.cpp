#include "transform/frames.h"


#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <thread>

#include "core/error.h"
#include "core/parallel.h"
#include "image/io.h"

namespace proctex::transform {

nlohmann::json Frame::to_json() const {
  nlohmann::json j = {{"spec", spec.to_json()}, {"position", position}};
  if (blend_to) {
    j["dissolve"] = {{"to", blend_to->to_json()}, {"blend", blend}};
  }
  if (key >= 0) j["key"] = key;
  if (jump) j["jump"] = true;
  j["similarity_to_previous"] = std::isnan(similarity) ? nlohmann::json() : nlohmann::json(similarity);
  j["layout_difference_to_previous"] = std::isnan(layout) ? nlohmann::json() : nlohmann::json(layout);
  return j;
}

nlohmann::json Quality::to_json() const {
  return {{"frames", frames},
          {"max_dissimilarity", max_dissimilarity},
          {"mean_dissimilarity", mean_dissimilarity},
          {"worst_step", worst_step},
          {"layout_mean", layout_mean},
          {"layout_max", layout_max}};
}

std::vector<metrics::Features> render_features(Renderer& renderer, const ShaderDecl& decl,
                                               const std::vector<std::vector<float>>& packed,
                                               const std::vector<uint32_t>& seeds, int resolution, int jobs) {
  RenderSettings rs;
  rs.width = rs.height = resolution;
  const auto images = renderer.render_batch(decl, packed, seeds, rs);
  std::vector<metrics::Features> out(images.size());
  const auto& metric = metrics::default_metric();
  parallel_for(images.size(), jobs, [&](size_t i) { out[i] = metric.features(images[i], resolution); });
  return out;
}

std::vector<Image> render_frames(const std::vector<Frame>& frames, size_t first, size_t count, Renderer& renderer,
                                 const RenderSettings& settings) {
  // Every render this range needs, grouped by shader so each shader is one launch (render_batch
  // splits large ones itself).
  struct Job {
    size_t frame;
    bool second;  // the blend_to end of a dissolve frame
  };
  std::map<std::string, std::vector<Job>> jobs;
  const size_t end = std::min(frames.size(), first + count);
  for (size_t f = first; f < end; ++f) {
    jobs[frames[f].spec.shader].push_back({f, false});
    if (frames[f].blend_to) jobs[frames[f].blend_to->shader].push_back({f, true});
  }
  std::vector<Image> a(end - first), b(end - first);
  for (const auto& [shader, list] : jobs) {
    const ShaderDecl& decl = renderer.library().get(shader);
    // Blended frames share their ends with their neighbours: each distinct vector renders once.
    std::map<std::pair<std::vector<float>, uint32_t>, size_t> unique;
    std::vector<std::vector<float>> packed;
    std::vector<uint32_t> seeds;
    std::vector<size_t> which(list.size());
    for (size_t k = 0; k < list.size(); ++k) {
      const TextureSpec& s = list[k].second ? *frames[list[k].frame].blend_to : frames[list[k].frame].spec;
      auto key = std::make_pair(resolve(decl, s), s.seed);
      auto [it, fresh] = unique.emplace(key, packed.size());
      if (fresh) {
        packed.push_back(key.first);
        seeds.push_back(s.seed);
      }
      which[k] = it->second;
    }
    const auto images = renderer.render_batch(decl, packed, seeds, settings);
    for (size_t k = 0; k < list.size(); ++k) (list[k].second ? b : a)[list[k].frame - first] = images[which[k]];
  }
  for (size_t f = first; f < end; ++f) {
    const Frame& fr = frames[f];
    if (!fr.blend_to) continue;
    Image& out = a[f - first];
    const Image& other = b[f - first];
    const float t = static_cast<float>(fr.blend);
    for (size_t i = 0; i < out.pixels.size(); ++i) out.pixels[i] += t * (other.pixels[i] - out.pixels[i]);
  }
  return a;
}

std::vector<double> dissolve_curve(const TextureSpec& a, const TextureSpec& b, Renderer& renderer, int resolution,
                                   int jobs, int samples) {
  samples = std::max(samples, 2);
  std::vector<Frame> ends(2);
  ends[0].spec = a;
  ends[1].spec = b;
  RenderSettings rs;
  rs.width = rs.height = resolution;
  const auto images = render_frames(ends, 0, 2, renderer, rs);
  const auto& metric = metrics::default_metric();
  std::vector<metrics::Features> f(samples + 1);
  parallel_for(f.size(), jobs, [&](size_t k) {
    Image blend = images[0];
    const float t = static_cast<float>(double(k) / samples);
    for (size_t i = 0; i < blend.pixels.size(); ++i) blend.pixels[i] += t * (images[1].pixels[i] - blend.pixels[i]);
    f[k] = metric.features(blend, resolution);
  });
  // Floored so that a flat stretch of the curve stays strictly increasing (invertible).
  std::vector<double> length(samples + 1, 0.0);
  for (int k = 1; k <= samples; ++k)
    length[k] = length[k - 1] + std::max(1e-9, -std::log(std::clamp(metric.similarity(f[k - 1], f[k]), 1e-4, 1.0)));
  return length;
}

std::vector<double> dissolve_blends(const std::vector<double>& curve, int count) {
  std::vector<double> out;
  const int samples = static_cast<int>(curve.size()) - 1;
  if (count <= 0 || samples < 1) return out;
  int k = 1;
  for (int d = 1; d <= count; ++d) {
    const double target = curve.back() * d / (count + 1);
    while (k < samples && curve[k] < target) ++k;
    const double t = (k - 1 + (target - curve[k - 1]) / (curve[k] - curve[k - 1])) / samples;
    out.push_back(std::clamp(t, 1e-6, 1 - 1e-6));
  }
  return out;
}

double layout_difference(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height || a.pixels.empty()) return 0;
  double s = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i)
    s += std::fabs(linear_to_srgb(std::clamp(a.pixels[i], 0.0f, 1.0f)) - linear_to_srgb(std::clamp(b.pixels[i], 0.0f, 1.0f)));
  return s / static_cast<double>(a.pixels.size());
}

Quality measure(std::vector<Frame>& frames, Renderer& renderer, int resolution, int jobs, std::vector<Image>* keep,
                int keep_size, const std::function<void(double)>& progress) {
  RenderSettings rs;
  rs.width = rs.height = resolution;
  const auto& metric = metrics::default_metric();
  Quality q;
  q.frames = static_cast<int>(frames.size());
  if (keep) keep->assign(frames.size(), Image());
  metrics::Features previous;
  Image previous_image;
  const size_t chunk = 32;
  double sum = 0;
  int steps = 0;
  for (size_t first = 0; first < frames.size(); first += chunk) {
    auto images = render_frames(frames, first, chunk, renderer, rs);
    std::vector<metrics::Features> features(images.size());
    parallel_for(images.size(), jobs, [&](size_t i) {
      features[i] = metric.features(images[i], resolution);
      if (keep) (*keep)[first + i] = resize(images[i], keep_size, keep_size);
    });
    for (size_t i = 0; i < images.size(); ++i) {
      Frame& f = frames[first + i];
      if (first + i > 0) {
        f.similarity = metric.similarity(previous, features[i]);
        f.layout = layout_difference(previous_image, images[i]);
        const double d = 1 - f.similarity;
        sum += d;
        ++steps;
        if (d > q.max_dissimilarity || q.worst_step < 0) {
          q.max_dissimilarity = d;
          q.worst_step = static_cast<int>(first + i);
        }
        q.layout_mean += f.layout;
        q.layout_max = std::max(q.layout_max, f.layout);
      }
      previous = std::move(features[i]);
      previous_image = std::move(images[i]);
    }
    if (progress) progress(std::min(1.0, double(first + chunk) / frames.size()));
  }
  if (steps > 0) {
    q.mean_dissimilarity = sum / steps;
    q.layout_mean /= steps;
  }
  return q;
}

void write_gif(const std::vector<Image>& frames, const std::filesystem::path& path, int fps) {
  if (frames.empty()) throw Error("no frames to write to '" + path.string() + "'");
  const int w = frames.front().width, h = frames.front().height;
  std::vector<std::vector<uint8_t>> codes;
  codes.reserve(frames.size());
  for (const Image& frame : frames) {
    const Image img = frame.width == w && frame.height == h ? frame : resize(frame, w, h);
    std::vector<uint8_t> bytes(size_t(w) * h * 3);
    for (size_t i = 0; i < bytes.size(); ++i)
      bytes[i] = static_cast<unsigned char>(std::lround(255 * linear_to_srgb(std::clamp(img.pixels[i], 0.0f, 1.0f))));
    codes.push_back(std::move(bytes));
  }
  write_animated_gif(path, codes, w, h, fps);
}

}  // namespace proctex::transform
