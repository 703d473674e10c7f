// @shader "Burlap (hessian): coarse, hairy, uneven plain weave with open gaps"
// @param int   threads      = 14   [4, 48]             "Threads along each side of the texture"
// @param float gap          = 0.3  [0.05, 0.6]         "Openness of the weave"
// @param float wobble       = 0.5  [0, 1]              "Waviness and uneven spacing of the threads"
// @param float slub         = 0.5  [0, 1]              "Thickness variation along and between threads"
// @param float hairiness    = 0.5  [0, 1]              "Fibrous streaks across the threads"
// @param color color        = (0.42, 0.30, 0.16)       "Jute colour (linear RGB)"
// @param color gap_color    = (0.03, 0.02, 0.01)       "Colour seen through the gaps"
// @param float variation    = 0.3  [0, 1]              "Thread-to-thread colour variation"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float n = (float)P.threads;
  float2 q = p * n;
  const float w = fw * n;
  q = pt_warp(q, w, 0.25f * P.wobble, 0.35f, 3, pt_subseed(seed, 1u));
  const float2 cell = pt_floor(q);
  const float2 f = q - cell - 0.5f;
  const int i = (int)cell.x, j = (int)cell.y;
  const int warp_on_top = ((i + j) & 1) == 0;
  // Slub: thickness varies along each thread (noise along its length) and between threads.
  const float sw = pt_gnoise((float2)(q.y * 0.7f, (float)i * 3.1f), pt_subseed(seed, 2u));
  const float sf = pt_gnoise((float2)(q.x * 0.7f, (float)j * 3.1f), pt_subseed(seed, 3u));
  const float h = 0.5f * (1.0f - P.gap);
  const float hw = h * (1.0f + 0.35f * P.slub * sw);
  const float hf = h * (1.0f + 0.35f * P.slub * sf);
  const float nw = pt_fbm((float2)(q.x * 8.0f, q.y * 1.5f), w * 8.0f, 3, 2.0f, 0.6f, pt_subseed(seed, 4u));
  const float nf = pt_fbm((float2)(q.x * 1.5f, q.y * 8.0f), w * 8.0f, 3, 2.0f, 0.6f, pt_subseed(seed, 5u));
  float3 warp = pt_vary_color(P.color, P.variation, pt_rand(i, 0, 6, seed), pt_rand(i, 0, 7, seed));
  float3 weft = pt_vary_color(P.color, P.variation, pt_rand(0, j, 8, seed), pt_rand(0, j, 9, seed));
  warp *= 1.0f + 0.7f * P.hairiness * nw;
  weft *= 1.0f + 0.7f * P.hairiness * nf;
  float3 c = pt_weave_cell(f, w, hw, hf, warp_on_top, 0.7f, warp, weft, P.gap_color);
  // Stray fibres crossing the gaps.
  const float hair = pt_fbm(q * 3.0f, w * 3.0f, 4, 2.0f, 0.5f, pt_subseed(seed, 6u));
  c = mix(c, P.color * 0.7f, 0.3f * P.hairiness * smoothstep(0.3f, 0.6f, hair));
  return pt_saturate3(c);
}
