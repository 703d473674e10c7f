// @shader "Herringbone paving: 2:1 bricks alternating horizontal and vertical, optionally at 45 degrees"
// @param float scale        = 10   [3, 40] log          "Brick widths across the texture"
// @param float mortar       = 0.1  [0.02, 0.4] log      "Joint width, fraction of a brick width"
// @param color brick        = (0.35, 0.14, 0.08)        "Mean brick colour (linear RGB)"
// @param color mortar_color = (0.40, 0.38, 0.35)        "Joint colour (linear RGB)"
// @param float variation    = 0.3  [0, 1]               "Brick-to-brick colour variation"
// @param float wear         = 0.3  [0, 1]               "Eroded edges and surface stains"
// @param float bevel        = 0.3  [0, 1]               "Darkening of the rounded brick edges"
// @param bool  diagonal     = false                     "Rotate the pattern by 45 degrees"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  float2 q = p * P.scale;
  const float w = fw * P.scale;
  if (P.diagonal) q = (float2)(0.70710678f * (q.x + q.y), 0.70710678f * (q.y - q.x));
  int vertical;
  int2 id;
  const float4 c = pt_herringbone(q, &vertical, &id);
  const float2 half_size = vertical ? (float2)(0.5f, 1.0f) : (float2)(1.0f, 0.5f);
  const float n = pt_fbm(q * 2.0f, w * 2.0f, 5, 2.0f, 0.55f, pt_subseed(seed, 1u));
  float d = pt_sd_round_box(c.zw, half_size - 0.5f * P.mortar, 0.04f + 0.06f * P.wear);
  d += P.wear * (0.02f + 0.06f * n);
  const float cover = pt_coverage(d, w);
  const uint bseed = pt_subseed(seed, (uint)vertical);
  float3 bc = pt_vary_color(P.brick, P.variation, pt_rand(id.x, id.y, 0, bseed), pt_rand(id.x, id.y, 1, bseed));
  bc *= 1.0f + P.wear * 0.5f * n;
  bc *= mix(1.0f, mix(1.0f - 0.5f * P.bevel, 1.0f, smoothstep(0.0f, 0.12f, -d)), pt_detail_weight(0.12f / w));
  const float3 mc = P.mortar_color * (1.0f + 0.25f * n);
  return pt_saturate3(mix(mc, bc, cover));
}
