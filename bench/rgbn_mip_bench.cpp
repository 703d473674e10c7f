// bench_rgbn_mip: relative L2 error of Blinn-Phong shading of normal-map MIP levels against the
// supersampled truth (Han et al. ch. 7), for footprints 2x2 .. 16x16 and exponents 8, 32, 128.
// Target (issue 14): the vMF mixture at least 30% below Toksvig where footprints hold several
// normal modes (2-8 texels), and never worse than Toksvig. Prints markdown tables.
//   bench_rgbn_mip [--size 256] [--lobes 6] [--iterations 12] [--seed 0]
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>

#include "rgbn/mip.h"
#include "rgbn/rgbn.h"
#include "rgbn/view.h"

using namespace proctex;
using namespace proctex::rgbn;

namespace {

// Every block of `block` x `block` texels takes one of `modes` facets (tilted 25 degrees, or
// alternately 15 and 35 when modes > 3) at random, each normal jittered by `jitter` degrees: a
// footprint larger than the block holds several normal modes.
Rgbn facets(int S, int block, unsigned seed, int modes = 3, float jitter = 0) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0, jitter);
  Rgbn r(S, S);
  const int nb = (S + block - 1) / block;
  std::vector<int> pick(size_t(nb) * nb);
  for (int& p : pick) p = int(rng() % modes);
  for (int y = 0; y < S; ++y)
    for (int x = 0; x < S; ++x) {
      const int k = pick[size_t(y / block) * nb + x / block];
      const float tilt = modes > 3 ? (k % 2 ? 35.0f : 15.0f) : 25.0f;
      const float az = 360.0f * k / modes + 15.0f + (jitter > 0 ? g(rng) * 3 : 0.0f);
      const Vec3 n = light_direction(az, 90.0f - tilt + (jitter > 0 ? g(rng) : 0.0f));
      std::copy(n.begin(), n.end(), r.n(x, y));
    }
  return r;
}

Rgbn bumps(int S) {
  HeightField z{S, S, std::vector<float>(size_t(S) * S, 0.0f)};
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 1);
  for (int k = 0; k < 12; ++k) {
    const int fx = 1 + int(u(rng) * 12), fy = int(u(rng) * 12);
    const float ph = u(rng) * 6.28f, a = 20.0f / (fx + fy);
    for (int y = 0; y < S; ++y)
      for (int x = 0; x < S; ++x) z.at(x, y) += a * std::sin(6.2831853f * (fx * x + fy * y) / float(S) + ph);
  }
  return from_height(z, 1.0f, true);
}

Rgbn brick(int S) {
  const Image photo = load_image(std::filesystem::path(PROCTEX_SHARED_DIR) / "textures" / "brick.png");
  const HeightField h = height_from_image(crop(photo, 0, 0, std::min(S, photo.width), std::min(S, photo.height)));
  return from_height(h, 8.0f, false);
}

}  // namespace

int main(int argc, char** argv) {
  int size = 256, lobes = MipOptions{}.lobes, iterations = MipOptions{}.iterations;
  unsigned seed = 0;  // added to the facet maps' seeds (robustness check: other random maps)
  for (int i = 1; i + 1 < argc; ++i) {
    if (!std::strcmp(argv[i], "--size")) size = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--lobes")) lobes = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--iterations")) iterations = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--seed")) seed = unsigned(std::atoi(argv[++i]));
  }
  struct Map {
    std::string name;
    Rgbn rgbn;
    bool multimodal;
  };
  const std::vector<Map> maps = {{"facets/1 (3 facets per texel)", facets(size, 1, 1 + seed), true},
                                 {"facets/3 (3 facets per 3x3 block)", facets(size, 3, 2 + seed), true},
                                 {"facets6+jitter (6 facets per texel, 4 deg jitter)", facets(size, 1, 3 + seed, 6, 4.0f), true},
                                 {"bumps (smooth sinusoids)", bumps(size), false},
                                 {"brick photo (height x8)", brick(size), false}};
  const std::vector<MipMethod> methods = {MipMethod::Naive, MipMethod::Toksvig, MipMethod::Vmf, MipMethod::Sh};
  MipOptions o;
  o.lobes = lobes;
  o.iterations = iterations;
  double worst_multi = 0, worst_all = 0;
  const auto start = std::chrono::steady_clock::now();
  for (const auto& m : maps) {
    std::printf("\n### %s, %dx%d, %d vMF lobes, SH order %d\n\n", m.name.c_str(), size, size, o.lobes, o.sh_order);
    std::printf("| footprint | exponent | naive | toksvig | vmf | sh | vmf / toksvig |\n|---|---|---|---|---|---|---|\n");
    for (int f : {2, 4, 8, 16}) {
      const MipLevel L = build_level(m.rgbn, f, o, true, true);
      for (float s : {8.0f, 32.0f, 128.0f}) {
        double e[4];
        for (int k = 0; k < 4; ++k) e[k] = mip_error(m.rgbn, L, methods[k], s);
        // Both methods exact (a footprint of one normal): no ratio to speak of.
        const double ratio = e[1] > 1e-4 ? e[2] / e[1] : (e[2] <= 1e-4 ? 0.0 : 1e9);
        if (m.multimodal && f <= 8) worst_multi = std::max(worst_multi, ratio);
        worst_all = std::max(worst_all, ratio);
        std::printf("| %d | %g | %.4f | %.4f | %.4f | %.4f | %.3f |\n", f, s, e[0], e[1], e[2], e[3], ratio);
      }
    }
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("\nworst vmf/toksvig on multi-modal footprints 2-8: %.3f (target <= 0.70)\n", worst_multi);
  std::printf("worst vmf/toksvig anywhere: %.3f (target <= 1.00)\n", worst_all);
  std::printf("total %.1f s\n", secs);
  return worst_multi <= 0.7 && worst_all <= 1.0 ? 0 : 1;
}
