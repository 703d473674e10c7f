// @shader "End grain: concentric growth rings of a sawn log with radial drying cracks"
// @param float rings       = 18   [4, 60] log          "Growth rings from the pith to the edge"
// @param float distortion  = 0.3  [0, 1]               "Wobble of the rings"
// @param float center_x    = 0.5  [0.2, 0.8]           "Pith position, x"
// @param float center_y    = 0.5  [0.2, 0.8]           "Pith position, y"
// @param float late_wood   = 0.3  [0.05, 0.9]          "Fraction of each ring that is dark late wood"
// @param float cracks      = 0.4  [0, 1]               "Radial drying cracks"
// @param float grain       = 0.3  [0, 1]               "Fine texture"
// @param color light_color = (0.60, 0.40, 0.20)        "Early wood colour (linear RGB)"
// @param color dark_color  = (0.35, 0.18, 0.07)        "Late wood colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 a = p - (float2)(P.center_x, P.center_y);
  float3 c = pt_wood(a, fw, P.rings, P.distortion, P.late_wood, 0.6f, P.grain, P.light_color,
                     P.dark_color, seed);
  // Cracks: a few radial wedges (angle bins with random width), widening outwards.
  const float r = length(a);
  const float ang = pt_atan2(a.y, a.x) * (1.0f / (2.0f * M_PI_F)) + 0.5f;  // [0, 1)
  const float bins = 9.0f;
  const float t = ang * bins;
  const float k = pt_floor(t);
  const float present = pt_rand((int)k, 0, 1, seed) < P.cracks ? 1.0f : 0.0f;
  const float centre = k + 0.3f + 0.4f * pt_rand((int)k, 0, 2, seed);
  const float len = 0.15f + 0.5f * pt_rand((int)k, 0, 3, seed);
  // Distance to the crack line in texture units (arc length), the crack tapers towards the pith.
  const float dist = fabs(t - centre) / bins * 2.0f * M_PI_F * r;
  const float width = 0.006f * clamp((r - (0.5f - len) * 0.8f) / 0.3f, 0.0f, 1.0f);
  const float crack = present * pt_coverage(dist - width, fw);
  c = mix(c, c * 0.15f, crack);
  return pt_saturate3(c);
}
