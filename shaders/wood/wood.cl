// @shader "Wood: growth rings around a pith, wobbled by noise, with fine grain (planks to end grain)"
// @param float rings       = 14   [2, 60] log         "Growth rings per texture unit"
// @param float stretch     = 3    [1, 30] log         "Elongation of the rings along the grain (1: end grain)"
// @param float pith        = -0.25 [-1.5, 0.5]         "Vertical position of the tree's centre (0: top edge)"
// @param float distortion  = 0.35 [0, 1]              "Noise that wobbles the rings"
// @param float late_wood   = 0.35 [0.05, 0.9]         "Fraction of each ring that is dark late wood"
// @param float softness    = 0.5  [0, 1]              "Softness of the ring edges"
// @param float grain       = 0.35 [0, 1]              "Fine pores and streaks along the grain"
// @param color light_color = (0.52, 0.30, 0.13)       "Early wood colour (linear RGB)"
// @param color dark_color  = (0.25, 0.11, 0.04)       "Late wood colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  // Coordinates across the tree: x along the grain is compressed by the stretch.
  const float2 a = (float2)((p.x - 0.5f) / P.stretch, p.y - P.pith);
  const float n = pt_fbm(a * 3.0f, fw * 3.0f, 5, 2.0f, 0.5f, pt_subseed(seed, 1u));
  float r = length(a) * P.rings + P.distortion * 1.5f * n;
  // Uneven ring widths: good and bad growth years.
  r += 0.5f * P.distortion * pt_gnoise((float2)(r * 0.37f, 0.5f), pt_subseed(seed, 4u));
  // |grad r| <= rings (the stretch only shrinks x) plus the noise's slope.
  const float wr = fw * (P.rings + P.distortion * 1.5f * 3.0f * 2.0f) * (1.0f + 0.4f * P.distortion);
  const float s = P.softness * fmin(P.late_wood, 1.0f - P.late_wood);
  const float late = pt_soft_pulsetrain(P.late_wood, r, wr, s);
  float3 c = mix(P.light_color, P.dark_color, late);

  // Grain: pores and streaks, long along the grain, fine across it.
  const float2 g = (float2)(a.x * 4.0f, length(a) * 60.0f);
  const float gn = pt_fbm(g + (float2)(0.0f, 15.0f * n), fw * 60.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 2u));
  const float slow = pt_fbm(a * (float2)(1.0f, 12.0f), fw * 12.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 3u));
  c *= 1.0f + P.grain * (0.35f * gn + 0.2f * slow) - 0.1f * P.grain * late;
  return pt_saturate3(c);
}
