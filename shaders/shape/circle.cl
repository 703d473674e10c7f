// @shader "A centred circle (or ring) on a background"
// @param float size     = 0.6  [0.05, 0.95]         "Diameter, fraction of the texture"
// @param float ring     = 0    [0, 1]               "Hollow ring: 0 filled, 1 thinnest outline"
// @param float softness = 0    [0, 0.5]             "Edge blur, fraction of the shape size"
// @param color fg       = (0.85, 0.20, 0.10)        "Shape colour (linear RGB)"
// @param color bg       = (0.90, 0.88, 0.82)        "Background colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float r = 0.5f * P.size;
  float d = pt_sd_circle(p - 0.5f, r);
  if (P.ring > 0.0f) {
    const float t = r * (1.0f - 0.9f * P.ring);  // ring thickness
    d = fmax(d, -(d + t));
  }
  return mix(P.bg, P.fg, pt_coverage(d, fw + P.softness * P.size));
}
