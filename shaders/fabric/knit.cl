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
  const float2 cell = floor(q);
  const float2 f = q - cell - (float2)(0.5f, 0.0f);
  // Each stitch is two legs of a V (pointing down) spanning about 1.5 rows; check this row and
  // the row above (its legs hang into this one). Keep the nearest leg (and its shading).
  const float r = 0.5f * P.thickness * 0.62f;
  float best = 1e9f, across = 0.0f;
  int bx = (int)cell.x, by = (int)cell.y;
  for (int dy = 0; dy <= 1; ++dy) {
    const float2 g = f + (float2)(0.0f, (float)dy);  // position relative to stitch (cell.y - dy)
    const float2 a0 = (float2)(-0.3f, -0.1f), b0 = (float2)(-0.04f, 1.0f);
    const float2 a1 = (float2)(0.3f, -0.1f), b1 = (float2)(0.04f, 1.0f);
    const float d0 = pt_sd_segment(g, a0, b0), d1 = pt_sd_segment(g, a1, b1);
    const float d = fmin(d0, d1);
    if (d < best) { best = d; by = (int)cell.y - dy; }
  }
  const float dist = best - r;
  const float cover = pt_coverage(dist, w);
  const float x = clamp(best / r, 0.0f, 1.0f);
  const float dw = pt_detail_weight(0.5f / w);
  const float shade_ = mix(0.75f, 1.0f - 0.6f * x * x, dw);
  float3 c = pt_vary_color(P.color, P.variation, pt_rand(bx, by, 0, seed), pt_rand(bx, by, 1, seed));
  // Twist: stripes slanted along each leg, plus fuzz.
  const float tw = pt_fbm(q * 6.0f, w * 6.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 2u));
  c *= shade_ * (1.0f + 0.5f * P.fuzz * tw);
  return pt_saturate3(mix(P.gap_color * (1.0f + 0.5f * tw), c, cover));
}
