#pragma once
// Filters that respect the surface (Pereira & Velho §1.4). Every linear filter runs on the slope
// field (p, q) = (-n_x/n_z, -n_y/n_z): since (z * g)_x = z_x * g, filtering the slopes of normals(z)
// with any kernel g gives exactly normals(z * g) - the filtered height field's normals - with no
// height reconstruction. Normals are renormalised after every operator.
#include <string>
#include <vector>

#include "rgbn/rgbn.h"

namespace proctex::rgbn {

enum class FilterKind {
  Smooth,   // G_sigma
  Sharpen,  // 1 + amount * (1 - G_sigma)          (all-pass + high-pass)
  Edge,     // 1 + amount * (G_sigma - G_sigma2)   (all-pass + band-pass)
  Detail,   // G_sigma - G_sigma2                  (band-pass alone: a detail "normal texture")
  Scale,    // amount * identity                   (gradient scaling: normals(amount * z))
};
FilterKind parse_filter_kind(const std::string& name);  // smooth, sharpen, edge, detail, scale
std::string filter_kind_name(FilterKind kind);

struct FilterOptions {
  FilterKind kind = FilterKind::Smooth;
  float sigma = 2.0f;    // pixels
  float sigma2 = 6.0f;   // the wider Gaussian of edge/detail (pixels, > sigma)
  float amount = 1.0f;   // sharpen/edge strength, or the gradient scale k
  bool wrap = false;     // periodic borders (tileable RGBNs); otherwise clamped
  bool albedo = false;   // filter the albedo with the same kernel (smooth/sharpen/edge only)
};

// A brush: per-pixel weight in [0, 1] (same size as the image). Pixels with weight 0 are copied
// unchanged, weight 1 takes the filtered value, between blends the normals and renormalises.
using Mask = std::vector<float>;

Rgbn filter(const Rgbn& image, const FilterOptions& options, const Mask* mask = nullptr);

// The general filter with an explicit kernel (odd width and height, row-major, top row first),
// applied to the slopes by direct convolution (periodic when `wrap`, else clamped borders).
Rgbn convolve(const Rgbn& image, const std::vector<float>& kernel, int kw, int kh, bool wrap,
              const Mask* mask = nullptr);

// Separable Gaussian blur of one scalar field in place (periodic or clamped borders).
void gaussian_blur(std::vector<float>& field, int w, int h, float sigma, bool wrap);

// Bilateral filter of colour and normals (§1.4): weights k_x(|xi - x|) k_c(|c(xi) - c(x)|)
// k_n(|n(xi) - n(x)|), Gaussians of widths sigma_s (pixels), sigma_c (linear colour distance)
// and sigma_n (normal chord distance). Small sigma_n keeps creases; large sigma_c, sigma_n give
// the Gaussian.
struct BilateralOptions {
  float sigma_s = 2.0f;
  float sigma_c = 0.1f;
  float sigma_n = 0.2f;
  bool albedo = true;  // also filter the albedo (with the same weights)
};
Rgbn bilateral(const Rgbn& image, const BilateralOptions& options, const Mask* mask = nullptr);

// Brush masks: a disc (soft edge of `feather` pixels), a rectangle, or a grey image (> 0 = inside).
Mask disc_mask(int w, int h, float cx, float cy, float radius, float feather = 0.0f);
Mask rect_mask(int w, int h, int x, int y, int rw, int rh);
Mask image_mask(const Image& image, int w, int h);

// Blends `filtered` into `original` by the mask (helper used by every masked operator).
void apply_mask(const Rgbn& original, Rgbn& filtered, const Mask& mask);

}  // namespace proctex::rgbn
