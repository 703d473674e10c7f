// @shader "Knitted fabric (stockinette): columns of V-shaped stitches of soft yarn"
// @param int   stitches  = 12   [4, 48]              "Stitch columns across the texture"
// @param float aspect    = 0.75 [0.5, 1.2]           "Stitch row height / column width"
// @param float thickness = 0.7  [0.3, 0.9]           "Yarn thickness"
// @param color color     = (0.50, 0.06, 0.05)        "Yarn colour (linear RGB)"
// @param color gap_color = (0.05, 0.01, 0.01)        "Colour between the stitches (linear RGB)"
// @param float fuzz      = 0.4  [0, 1]               "Fibre fuzz and twist texture"
// @param float variation = 0.15 [0, 1]               "Stitch-to-stitch tension and colour variation"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float n = (float)P.stitches;
  const float2 q = (float2)(p.x * n, p.y * n / P.aspect);  // one stitch is 1 x 1 here
  const float w = fw * n / fmin(P.aspect, 1.0f);
  const float2 cell = pt_floor(q);
  // Each stitch is a V of two tilted, lens-shaped legs that meet at the bottom and spill a little
  // into the rows above and below; keep the leg whose outline is nearest (deepest inside).
  const float hl = 0.62f, hw = 0.5f * P.thickness * 0.62f;
  const float2 axis = (float2)(0.40f, 0.916f);  // leg direction, leaning outwards at the top
  float best = 1e9f, across = 0.0f, along = 0.0f;
  int bx = (int)cell.x, by = (int)cell.y;
  for (int dy = -1; dy <= 1; ++dy)
    for (int side = 0; side <= 1; ++side) {
      const float sx = side ? 1.0f : -1.0f;
      const float2 c = cell + (float2)(0.5f + sx * 0.2f, 0.5f + (float)dy);
      const float2 d = q - c;
      const float2 ax = (float2)(-sx * axis.x, axis.y);           // along the leg (screen y down)
      const float2 l = (float2)(d.x * ax.y - d.y * ax.x, dot(d, ax));
      const float sd = pt_sd_leaf(l, hl, hw);
      if (sd < best) { best = sd; across = l.x / hw; along = l.y / hl; by = (int)cell.y + dy; }
    }
  const float cover = pt_coverage(best, w);
  const float dw = pt_detail_weight(hw / w);
  const float x2 = clamp(across * across, 0.0f, 1.0f);
  const float shade_ = mix(0.78f, (1.0f - 0.55f * x2) * (1.0f - 0.3f * along * along), dw);
  float3 c = pt_vary_color(P.color, P.variation, pt_rand(bx, by, 0, seed), pt_rand(bx, by, 1, seed));
  // Twist of the yarn and fuzz.
  const float tw = pt_fbm(q * 6.0f, w * 6.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 2u));
  c *= shade_ * (1.0f + 0.5f * P.fuzz * tw);
  return pt_saturate3(mix(P.gap_color * (1.0f + 0.5f * tw), c, cover));
}
