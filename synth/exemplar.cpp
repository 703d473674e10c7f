#include "synth/exemplar.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"

namespace proctex::synth {
namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

void check_finite(const Image& image, const std::string& name) {
  for (float v : image.pixels) {
    if (!std::isfinite(v)) {
      throw Error(fmt::format("exemplar '{}' has non-finite pixels (NaN or infinity)", name),
                  "clean the image (e.g. clamp it in an image editor) and save it again");
    }
  }
}

void check_size(int w, int h, const std::string& name) {
  if (w < kMinExemplarSide || h < kMinExemplarSide) {
    throw Error(fmt::format("exemplar '{}' is {}x{}, smaller than {} px on a side", name, w, h, kMinExemplarSide),
                "use an exemplar of at least 16x16 pixels that shows several repeats of the texture");
  }
  if (w > kMaxExemplarSide || h > kMaxExemplarSide) {
    throw Error(fmt::format("exemplar '{}' is {}x{}, larger than {} px on a side", name, w, h, kMaxExemplarSide),
                "crop or resize it to at most 512x512 (synthesis copies at the exemplar's pixel scale, "
                "so resize it to the scale you want in the output)");
  }
}

}  // namespace

void validate(const Exemplar& ex) {
  check_size(ex.colour.width, ex.colour.height, ex.name);
  check_finite(ex.colour, ex.name);
  for (const auto& m : ex.maps) {
    if (m.image.width != ex.colour.width || m.image.height != ex.colour.height) {
      throw Error(fmt::format("map '{}' is {}x{} but the exemplar '{}' is {}x{}", m.name, m.image.width,
                              m.image.height, ex.name, ex.colour.width, ex.colour.height),
                  "every --apply map must be pixel-aligned with the exemplar (same size)");
    }
    check_finite(m.image, m.name);
  }
  if (!(ex.map_weight >= 0.0f) || !std::isfinite(ex.map_weight)) {
    throw UsageError("the map weight must be a finite number >= 0");
  }
}

Image load_exemplar_image(const std::filesystem::path& path) {
  ImageLimits limits;
  limits.max_dimension = 1 << 15;
  Image image = load_image(path, limits);
  check_size(image.width, image.height, path.filename().string());
  check_finite(image, path.filename().string());
  return image;
}

MapKind parse_map_kind(const std::string& kind, const std::string& file_name) {
  const std::string k = lower(kind);
  if (k == "normal" || k == "normals") return MapKind::Normal;
  if (k == "grey" || k == "gray" || k == "height" || k == "roughness" || k == "displacement" || k == "ao" ||
      k == "specular" || k == "mask")
    return MapKind::Grey;
  if (k == "colour" || k == "color" || k == "rgb" || k == "albedo") return MapKind::Colour;
  if (!k.empty()) {
    throw UsageError(fmt::format("unknown map kind '{}'", kind),
                     "use normal, height, roughness, grey or colour, e.g. --apply normal=n.png:out_n.png");
  }
  const std::string f = lower(std::filesystem::path(file_name).filename().string());
  if (f.find("normal") != std::string::npos || f.find("_nrm") != std::string::npos) return MapKind::Normal;
  for (const char* grey : {"height", "rough", "disp", "spec", "_ao", "bump", "gloss", "metal"}) {
    if (f.find(grey) != std::string::npos) return MapKind::Grey;
  }
  return MapKind::Colour;
}

Channels matching_channels(const Exemplar& ex) {
  Channels ch;
  ch.width = ex.width();
  ch.height = ex.height();
  const size_t n = static_cast<size_t>(ch.width) * ch.height;
  auto add_plane = [&](auto&& value) {
    const size_t base = ch.data.size();
    ch.data.resize(base + n);
    for (size_t i = 0; i < n; ++i) ch.data[base + i] = value(i);
    ++ch.count;
  };
  const auto& px = ex.colour.pixels;
  for (int c = 0; c < 3; ++c) add_plane([&](size_t i) { return linear_to_srgb(std::clamp(px[3 * i + c], 0.0f, 1.0f)); });
  const float w = ex.map_weight;
  for (const auto& m : ex.maps) {
    const auto& mp = m.image.pixels;
    switch (m.kind) {
      case MapKind::Colour:
        for (int c = 0; c < 3; ++c)
          add_plane([&](size_t i) { return w * linear_to_srgb(std::clamp(mp[3 * i + c], 0.0f, 1.0f)); });
        break;
      case MapKind::Normal:
        ch.normal_groups.push_back(ch.count);
        ch.normal_scale.push_back(w);
        // 8/16-bit files were linearised on load: undo it to get the stored code, then [-1, 1].
        for (int c = 0; c < 3; ++c)
          add_plane([&](size_t i) { return w * (2.0f * linear_to_srgb(std::clamp(mp[3 * i + c], 0.0f, 1.0f)) - 1.0f); });
        break;
      case MapKind::Grey:
        add_plane([&](size_t i) {
          const float g = (mp[3 * i] + mp[3 * i + 1] + mp[3 * i + 2]) / 3.0f;
          return w * linear_to_srgb(std::clamp(g, 0.0f, 1.0f));
        });
        break;
    }
  }
  return ch;
}

}  // namespace proctex::synth
