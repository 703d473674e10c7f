// @shader "Cobblestones: rows of domed, irregular setts with dark joints"
// @param int   rows         = 8    [3, 30]              "Rows of stones across the texture"
// @param float ratio        = 1.4  [0.8, 2.5]           "Stone length / stone height"
// @param float gap          = 0.12 [0.03, 0.4] log      "Joint width, fraction of a stone height"
// @param float roundness    = 0.6  [0, 1]               "Rounded corners and domed shading"
// @param float irregularity = 0.5  [0, 1]               "Wobbly outlines, random sizes and row shifts"
// @param color stone_color  = (0.30, 0.29, 0.28)        "Mean stone colour (linear RGB)"
// @param color gap_color    = (0.06, 0.055, 0.05)       "Joint colour (linear RGB)"
// @param float variation    = 0.4  [0, 1]               "Stone-to-stone colour variation"
// @param float roughness    = 0.4  [0, 1]               "Surface speckle and wear"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float rows = (float)P.rows;
  float2 q = p * rows;
  const float w = fw * rows;
  q = pt_warp(q, w, 0.12f * P.irregularity, 1.3f, 3, pt_subseed(seed, 1u));
  const float row = pt_floor(q.y);
  const float shift = 0.5f + 0.45f * P.irregularity * (pt_rand(0, (int)row, 5, seed) - 0.5f);
  const float4 c = pt_brick_cell((float2)(q.x + row * (shift - 0.5f) * P.ratio, q.y), P.ratio, 0.5f);
  const int cx = (int)c.x, cy = (int)c.y;
  const float r1 = pt_rand(cx, cy, 0, seed), r2 = pt_rand(cx, cy, 1, seed);
  const float2 lp = c.zw - (float2)(0.5f * P.ratio, 0.5f);
  const float2 half_size = (float2)(0.5f * P.ratio, 0.5f) - 0.5f * P.gap -
                           0.08f * P.irregularity * (float2)(r1, r2);
  const float d = pt_sd_round_box(lp, half_size, P.roundness * 0.45f);
  const float cover = pt_coverage(d, w);
  float3 sc = pt_vary_color(P.stone_color, P.variation, r1, r2);
  const float dome = smoothstep(0.0f, 0.45f, -d);
  sc *= mix(1.0f, 0.35f + 0.65f * sqrt(dome), P.roundness * pt_detail_weight(0.45f / w));
  const float n = pt_fbm(q * 3.0f, w * 3.0f, 4, 2.0f, 0.6f, pt_subseed(seed, 2u));
  sc *= 1.0f + P.roughness * 0.5f * n;
  const float3 gc = P.gap_color * (1.0f + 0.4f * n);
  return pt_saturate3(mix(gc, sc, cover));
}
