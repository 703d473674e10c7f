// @shader "Brick wall: running/stack/English/Flemish bonds, mortar joints, per-brick colour and worn edges"
// @param int   rows         = 10   [2, 40]                     "Brick courses (rows) across the texture"
// @param float ratio        = 2.0  [1.0, 6.0]                  "Brick length divided by brick height"
// @param float mortar       = 0.12 [0.02, 0.4] log             "Mortar joint width, fraction of the brick height"
// @param color brick        = (0.33, 0.11, 0.06)               "Mean brick colour (linear RGB)"
// @param color mortar_color = (0.45, 0.43, 0.40)               "Mortar colour (linear RGB)"
// @param float variation    = 0.35 [0, 1]                      "Brick-to-brick colour variation"
// @param float wear         = 0.3  [0, 1]                      "Chipped, eroded brick edges"
// @param float roughness    = 0.3  [0, 1]                      "Surface grain and stains"
// @param bool  vertical     = false                            "Courses run vertically (wall turned 90 degrees)"
// @param enum  bond         = running {running, stack, english, flemish} "Bond pattern"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float rows = (float)P.rows;
  const float2 q = (P.vertical ? p.yx : p) * rows;  // one course is 1 unit high
  const float w = fw * rows;  // footprint in course units
  float len;
  const float4 c = pt_bond_cell(q, P.ratio, P.bond, &len);
  const int cx = (int)c.x, cy = (int)c.y;
  const float2 lp = c.zw - (float2)(0.5f * len, 0.5f);
  const float half_m = 0.5f * P.mortar;
  const float2 half_size = fmax((float2)(0.5f * len - half_m, 0.5f - half_m), (float2)(0.02f));

  // One noise field drives edge wear and the mortar's texture; it is continuous across joints.
  const float n = pt_fbm(q * 1.5f, w * 1.5f, 6, 2.0f, 0.55f, pt_subseed(seed, 1u));
  float d = pt_sd_round_box(lp, half_size, 0.03f + 0.08f * P.wear);
  d += P.wear * (0.025f + 0.12f * n);  // positive noise eats into the brick
  const float cover = pt_coverage(d, w);

  // Brick colour: per-brick random tint and brightness, then stains and grain.
  const float r1 = pt_rand(cx, cy, 0, seed), r2 = pt_rand(cx, cy, 1, seed);
  float3 bc = pt_vary_color(P.brick, P.variation, r1, r2);
  const float stain = n + 0.5f * (pt_rand(cx, cy, 2, seed) - 0.5f);
  // Fine grain: one octave of small-scale noise, faded out below two pixels.
  const float fine = pt_octave_weight(12.0f, w) * pt_gnoise(q * 12.0f, pt_subseed(seed, 2u));
  bc *= 1.0f + P.roughness * (0.6f * stain + 0.35f * fine);
  // Slightly darker rim where the brick face turns into the joint.
  bc *= mix(1.0f, 0.8f + 0.2f * smoothstep(0.0f, 0.12f, -d), pt_detail_weight(0.12f / w));

  const float3 mc = P.mortar_color * (1.0f + 0.25f * n + 0.3f * P.roughness * fine);
  return pt_saturate3(mix(mc, bc, cover));
}
