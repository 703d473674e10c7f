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
  return pt_saturate3(pt_wood(a, fw, P.rings, P.distortion, P.late_wood, P.softness, P.grain,
                              P.light_color, P.dark_color, seed));
}
