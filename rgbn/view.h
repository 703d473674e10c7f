#pragma once
// Shaded renders and the paper's views of an RGBN (§1.6 UI): shaded (Lambert, Blinn-Phong),
// albedo, colour-coded normals, needles, signed scalar maps (curvature), segment labels.
// Every view returns a linear-RGB proctex::Image (save_image writes sRGB PNGs).
#include <string>
#include <vector>

#include "rgbn/rgbn.h"

namespace proctex::rgbn {

// Unit vector towards the light from an azimuth (degrees, 0 = +X right, 90 = +Y up) and an
// elevation above the image plane (degrees, 90 = straight on from the viewer).
Vec3 light_direction(float azimuth_deg, float elevation_deg);
// Parses "az,el" (degrees) or "x,y,z" (normalised); Error for a zero or non-finite vector.
Vec3 parse_light(const std::string& text);

enum class Shading { Lambert, BlinnPhong };
struct ShadeOptions {
  Shading model = Shading::Lambert;
  Vec3 light = light_direction(135.0f, 45.0f);  // from the upper left
  float intensity = 1.0f;
  float ambient = 0.05f;
  float specular = 0.3f;     // Blinn-Phong k_s (white highlight)
  float exponent = 32.0f;    // Blinn-Phong exponent
  bool use_albedo = true;    // false: shade a grey 0.8 surface (the "shaded normals" view)
};
// albedo * (ambient + intensity * max(0, n.l)) [+ k_s * intensity * max(0, n.h)^s], view +Z.
Image shade(const Rgbn& image, const ShadeOptions& options);

Image view_albedo(const Rgbn& image);
// (n + 1) / 2 shown as colours (the familiar bluish normal-map look, OpenGL convention).
Image view_normals(const Rgbn& image);
// Needles: the shaded normals with a line per `spacing` pixels along the projected normal.
Image view_needles(const Rgbn& image, int spacing = 12);
// A signed scalar map as blue (negative) - white (0) - red (positive), scaled by `range`
// (<= 0: the 99th percentile of |v|).
Image view_signed(const std::vector<float>& values, int w, int h, float range = 0.0f);
// Segment labels as distinct colours.
Image view_labels(const std::vector<int>& labels, int w, int h);

}  // namespace proctex::rgbn
