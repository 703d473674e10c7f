// @shader "Stone wall (ashlar/rubble): courses of irregular rectangular stones of random lengths"
// @param int   courses       = 7    [2, 24]             "Courses (rows) across the texture"
// @param float length        = 1.8  [0.8, 4]            "Mean stone length / course height"
// @param float irregularity  = 0.5  [0, 1]             "Random lengths, course heights and wobbly outlines"
// @param float mortar        = 0.1  [0.02, 0.4] log     "Joint width, fraction of a course"
// @param color stone_color   = (0.42, 0.38, 0.32)      "Mean stone colour (linear RGB)"
// @param color mortar_color  = (0.20, 0.19, 0.17)      "Joint colour (linear RGB)"
// @param float variation     = 0.35 [0, 1]             "Stone-to-stone colour variation"
// @param float relief        = 0.5  [0, 1]             "Rough, rounded stone faces (shading)"
// @param float roughness     = 0    [0, 1]             "Split, pitted stone faces: detail at every scale down to the pixel"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float n_c = (float)P.courses;
  float2 q = p * n_c;
  const float w = fw * n_c;
  q = pt_warp(q, w, 0.08f * P.irregularity, 1.5f, 2, pt_subseed(seed, 1u));
  const float row = pt_floor(q.y);
  const int iy = (int)row;
  // Stones of random length along each course: cut points at cells of mean length with jitter.
  const float L = P.length;
  const float x = q.x / L + pt_rand(0, iy, 5, seed) * 7.0f;
  const float k = pt_floor(x);
  const float j0 = 0.5f * P.irregularity * (pt_rand((int)k, iy, 1, seed) - 0.5f);
  const float j1 = 0.5f * P.irregularity * (pt_rand((int)k + 1, iy, 1, seed) - 0.5f);
  float a = k + j0, b = k + 1.0f + j1;
  int ix = (int)k;
  if (x < a) { b = a; a = k - 1.0f + 0.5f * P.irregularity * (pt_rand((int)k - 1, iy, 1, seed) - 0.5f); ix -= 1; }
  else if (x >= b) { a = b; b = k + 2.0f + 0.5f * P.irregularity * (pt_rand((int)k + 2, iy, 1, seed) - 0.5f); ix += 1; }
  const float cx = 0.5f * (a + b) * L, hx = 0.5f * (b - a) * L;
  const float2 lp = (float2)(x * L - cx, q.y - row - 0.5f);
  const float hy = 0.5f - 0.25f * P.irregularity * pt_rand(ix, iy, 2, seed) * 0.5f;
  const float d = pt_sd_round_box(lp, (float2)(hx, hy) - 0.5f * P.mortar, 0.05f + 0.15f * P.relief);
  const float cover = pt_coverage(d, w);
  float3 sc = pt_vary_color(P.stone_color, P.variation, pt_rand(ix, iy, 3, seed), pt_rand(ix, iy, 4, seed));
  const float nf = pt_fbm(q * 2.5f, w * 2.5f, 5, 2.0f, 0.55f, pt_subseed(seed, 2u));
  sc *= 1.0f + P.relief * 0.45f * nf;
  sc *= mix(1.0f, 0.6f + 0.4f * smoothstep(0.0f, 0.25f, -d), P.relief * pt_detail_weight(0.25f / w));
  // Split faces: chipped and pitted at every scale down to the pixel, as photographed ashlar is.
  // Without them only many small stones put a photo's fine detail into a render, and matches of
  // stone-wall photos came back with stones about 3x too small. Default 0: specs written before
  // the parameter existed render as they did, and without paying for the noise.
  if (P.roughness > 0.0f) {
    const float pits = pt_turbulence(q * 3.0f, w * 3.0f, 7, 2.0f, 0.62f, pt_subseed(seed, 3u));
    sc *= mix(1.0f, 0.35f + 2.6f * pits, P.roughness);
  }
  const float3 mc = P.mortar_color * (1.0f + 0.3f * nf);
  return pt_saturate3(mix(mc, sc, cover));
}
