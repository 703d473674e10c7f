// @shader "Layered noise through a three-colour ramp: fBm, turbulence or ridged, warped and stretched"
// @param enum  noise     = fbm {fbm, turbulence, ridged}  "Kind of fractal noise"
// @param float scale     = 4    [0.5, 16] log      "Features across the texture"
// @param float roughness = 0.5  [0.3, 0.7]         "Amplitude ratio between octaves (detail)"
// @param float warp      = 0    [0, 1]             "Domain warping (swirly distortion)"
// @param float stretch   = 1    [0.25, 4] log      "Horizontal stretch of the features"
// @param float contrast  = 0.35 [0, 1]             "Contrast of the ramp lookup"
// @param float bias      = 0.5  [0.25, 0.75]         "Midpoint of the ramp: shifts towards colour A or C"
// @param color color_a   = (0.05, 0.05, 0.05)      "Ramp colour for low values (linear RGB)"
// @param color color_b   = (0.35, 0.35, 0.35)      "Ramp colour for middle values (linear RGB)"
// @param color color_c   = (0.80, 0.80, 0.80)      "Ramp colour for high values (linear RGB)"
// @param int   octaves   = 6    [1, 9] fixed       "Octaves"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float sx = sqrt(P.stretch);
  float2 q = (float2)(p.x / sx, p.y * sx) * P.scale;
  const float w = fw * P.scale * fmax(sx, 1.0f / sx);
  if (P.warp > 0.0f) q = pt_warp(q, w, 0.8f * P.warp, 0.7f, 3, pt_subseed(seed, 7u));
  float v;
  if (P.noise == NOISE_TURBULENCE) {
    v = 0.5f + 1.9f * (pt_turbulence(q, w, P.octaves, 2.0f, P.roughness, seed) - 0.25f);
  } else if (P.noise == NOISE_RIDGED) {
    v = 0.5f + 1.0f * (pt_ridged(q, w, P.octaves, 2.0f, P.roughness, seed) - 0.545f);
  } else {
    v = 0.5f + 1.1f * pt_fbm(q, w, P.octaves, 2.0f, P.roughness, seed);
  }
  // Each noise is centred on 0.5 with a spread of about 0.19 (measured), then contrast around the
  // bias point, then the ramp.
  const float k = mix(0.5f, 3.0f, P.contrast);
  const float t = clamp(0.5f + (v - P.bias) * k, 0.0f, 1.0f);
  return pt_ramp3(t, P.color_a, P.color_b, P.color_c);
}
