#pragma once
// Normal-map filtering for display (Han et al., ch. 7 of the seed thesis): a coarse texel stands
// for a footprint of f x f fine normals, and shading it with the averaged normal (the naive MIP)
// loses the highlights' spread. Representations of the footprint's normal distribution (NDF):
//  - naive:   the normalised mean normal;
//  - toksvig: the mean normal's length |m| gives f_t = |m| / (|m| + s (1 - |m|)); the lobe becomes
//             f_t (n.h)^(f_t s);
//  - vmf:     a mixture of J von Mises-Fisher lobes (alpha_j, mu_j, kappa_j) fitted by spherical EM;
//             each lobe convolved with the Blinn-Phong lobe gives
//             alpha_j * k_j (mu_j.h)^(k_j s), k_j = kappa_j / (kappa_j + s);
//  - sh:      the NDF projected on real spherical harmonics up to order L, convolved with the lobe
//             (Funk-Hecke);
//  - truth:   the mean of (n.h)^s over the fine normals (supersampling), what every method
//             approximates.
#include <string>
#include <vector>

#include "rgbn/rgbn.h"

namespace proctex::rgbn {

enum class MipMethod { Naive, Toksvig, Vmf, Sh };
MipMethod parse_mip_method(const std::string& name);
std::string mip_method_name(MipMethod m);

struct VmfLobe {
  float alpha = 0;
  Vec3 mu{0, 0, 1};
  float kappa = 0;
};

// One coarse level for footprint f (the fine image is cropped to a multiple of f).
struct MipLevel {
  int footprint = 1;
  int width = 0, height = 0;
  std::vector<Vec3> mean;                 // unnormalised mean normal per coarse texel
  std::vector<std::vector<VmfLobe>> vmf;  // per texel (vmf method)
  std::vector<std::vector<float>> sh;     // per texel (sh method): (L+1)^2 coefficients
  int sh_order = 0;
};

struct MipOptions {
  int lobes = 6;       // vMF lobes per texel (at most the number of fine normals); 4 was too few
                       // for footprints of 6 modes or smooth steep bumps (docs/rgbn.md)
  int iterations = 12; // spherical EM iterations
  int sh_order = 6;
};

// Builds the level for footprint f with the data every method needs (mean; vMF if vmf; SH if sh).
MipLevel build_level(const Rgbn& fine, int footprint, const MipOptions& options, bool vmf, bool sh);

// Blinn-Phong specular lobe (n.h)^s of coarse texel i for half vector h under a method.
float mip_specular(const MipLevel& level, size_t texel, MipMethod method, const Vec3& h, float s);
// Ground truth: the mean of max(0, n.h)^s over the texel's fine normals.
float truth_specular(const Rgbn& fine, int footprint, int cx, int cy, const Vec3& h, float s);

// Spherical EM fit of J vMF lobes to unit vectors (deterministic: farthest-point start).
std::vector<VmfLobe> fit_vmf(const std::vector<Vec3>& normals, int lobes, int iterations);

// Relative L2 error sqrt(sum (approx - truth)^2 / sum truth^2) of the specular term over every
// coarse texel and a fixed set of half vectors (64 directions, elevation >= 30 degrees).
double mip_error(const Rgbn& fine, const MipLevel& level, MipMethod method, float exponent);

// The naive level as an RGBN (normalised mean normals, mean albedo).
Rgbn naive_level(const Rgbn& fine, int footprint);
// Writes a level as an EXR: naive/toksvig as N.X,N.Y,N.Z (Toksvig's unnormalised mean, whose
// length encodes the spread), vmf as lobeJ.{A,X,Y,Z,K}, sh as sh.K channels.
void save_level(const MipLevel& level, MipMethod method, const std::filesystem::path& path);

}  // namespace proctex::rgbn
