#pragma once
// RGBN images: a linear albedo colour and a unit normal per pixel (Pereira & Velho, "Editing
// RGBNs"). Normals are in the image frame: +X right, +Y up, +Z towards the viewer (the OpenGL
// convention, DESIGN.md "Surface"). Pixel rows run top to bottom, so +Y points to the row above.
//
// A height field z(x, y) (in pixel units, y up) has normals N = (-z_x, -z_y, 1) / |.|; its slopes
// are therefore p = z_x = -n_x / n_z and q = z_y = -n_y / n_z. Filters and curvature work on (p, q).
#include <array>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "image/image.h"

namespace proctex::rgbn {

using Vec3 = std::array<float, 3>;

struct Rgbn {
  int width = 0;
  int height = 0;
  std::vector<float> albedo;  // 3 floats per pixel, linear RGB, row-major, top row first
  std::vector<float> normal;  // 3 floats per pixel, unit length

  Rgbn() = default;
  // Albedo `grey`, every normal (0, 0, 1).
  Rgbn(int w, int h, float grey = 0.5f);

  size_t size() const { return size_t(width) * size_t(height); }
  bool empty() const { return width <= 0 || height <= 0; }
  float* n(int x, int y) { return normal.data() + 3 * (size_t(y) * width + x); }
  const float* n(int x, int y) const { return normal.data() + 3 * (size_t(y) * width + x); }
  float* a(int x, int y) { return albedo.data() + 3 * (size_t(y) * width + x); }
  const float* a(int x, int y) const { return albedo.data() + 3 * (size_t(y) * width + x); }
};

// Normalises every normal in place; zero or non-finite normals become (0, 0, 1).
void normalize_normals(Rgbn& image);
// Largest | |n| - 1 | over the image (0 for a valid RGBN).
double max_norm_error(const Rgbn& image);

// --- native file: EXR with channels R, G, B (albedo) and N.X, N.Y, N.Z (float) -------------
// Throws proctex::Error when a channel is missing, sizes disagree, or a normal is non-finite or
// further than `tolerance` from unit length (renormalised when within it).
Rgbn load_rgbn(const std::filesystem::path& path, double tolerance = 1e-2);
// Atomic write (temporary file + rename): a failure never leaves a half file.
void save_rgbn(const Rgbn& image, const std::filesystem::path& path);

// --- normal maps --------------------------------------------------------------------------------
// OpenGL: +Y up (green grows towards the top of the image). DirectX: +Y down (green inverted).
enum class Convention { OpenGL, DirectX };
Convention parse_convention(const std::string& name);  // "gl"/"opengl", "dx"/"directx"
std::string convention_name(Convention c);

// Encodes normals as a colour map: c = (n + 1) / 2 per channel (8-bit: round((x+1)*127.5)).
// .png/.tif are written with `bits` = 8 or 16 per channel (raw values, no sRGB curve),
// .exr as float n (no offset). DirectX flips the Y component.
void save_normal_map(const Rgbn& image, const std::filesystem::path& path, Convention convention,
                     int bits = 8);
// Decodes a normal-map file written in `convention` (8/16-bit PNG/TIFF: (c * 2 - 1); EXR/float
// TIFF: the values as they are) and renormalises. `albedo` is used when given (same size, else
// Error), otherwise the albedo is grey 0.5. Throws for a (near-)zero or non-finite normal.
Rgbn load_normal_map(const std::filesystem::path& path, Convention convention,
                     const Image* albedo = nullptr);

// Sets the albedo from an image of the same size (Error otherwise).
void set_albedo(Rgbn& image, const Image& albedo);
Image albedo_image(const Rgbn& image);

// --- height fields ------------------------------------------------------------------------------
// Heights in pixel units, row-major, top row first; y up as in the normal frame.
struct HeightField {
  int width = 0;
  int height = 0;
  std::vector<float> z;
  float& at(int x, int y) { return z[size_t(y) * width + x]; }
  float at(int x, int y) const { return z[size_t(y) * width + x]; }
};

// Normals of `scale * z` from central differences; `wrap` treats the field as tileable (periodic
// differences at the edges), otherwise one-sided differences at the border.
Rgbn from_height(const HeightField& z, float scale = 1.0f, bool wrap = false);
// The grey (luminance) of an image as a height field scaled to [0, 1].
HeightField height_from_image(const Image& image);

// Slopes p = -n_x/n_z, q = -n_y/n_z, with n_z clamped below at `min_nz` (grazing normals).
void slopes(const Rgbn& image, std::vector<float>& p, std::vector<float>& q, float min_nz = 0.05f);
// Sets the normals from slopes: n = (-p, -q, 1) / |.|.
void set_slopes(Rgbn& image, const std::vector<float>& p, const std::vector<float>& q);

struct Integration {
  HeightField z;          // zero mean
  double integrability;   // mean |dq/dx - dp/dy| over the image (curl of the slope field)
  double residual;        // RMS difference between the slopes of z and the RGBN's slopes
};
// Least-squares height from the normals by FFT (Frankot-Chellappa). `periodic` assumes a tileable
// field; otherwise the slope field is mirrored to twice the size first (no wrap-around seams).
Integration to_height(const Rgbn& image, bool periodic = false);

// Mean |dq/dx - dp/dy| (central differences, interior pixels): 0 for the normals of a height
// field, larger when edits made the field non-integrable. Over the pixels where `mask` is
// non-zero when given (same size).
double integrability_error(const Rgbn& image, const std::vector<float>* mask = nullptr);

}  // namespace proctex::rgbn

namespace proctex::rgbn::detail {
// Float EXR with named channels (atomic write), and reading named channels back (Error when one
// is missing). Used by the PTM and MIP files.
void write_exr(const std::filesystem::path& path, int w, int h, const std::vector<std::string>& channels,
               const std::vector<float>& interleaved);
std::vector<float> read_exr(const std::filesystem::path& path, const std::vector<std::string>& channels, int& w,
                            int& h);
}  // namespace proctex::rgbn::detail
