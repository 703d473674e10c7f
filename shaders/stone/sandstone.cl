// @shader "Sandstone: wavy sedimentary strata in a colour ramp with sandy grain"
// @param float bands    = 10   [2, 30] log          "Strata across the texture"
// @param float warp     = 0.4  [0, 1]               "Waviness of the strata"
// @param float tilt     = 0    [-40, 40]            "Tilt of the strata in degrees"
// @param color color_a  = (0.55, 0.30, 0.15)        "Ramp colour: dark strata"
// @param color color_b  = (0.75, 0.50, 0.30)        "Ramp colour: middle"
// @param color color_c  = (0.85, 0.72, 0.55)        "Ramp colour: light strata"
// @param float contrast = 0.6  [0.1, 1]               "Contrast between strata"
// @param float grain    = 0.4  [0, 1]               "Sandy grain"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float a = radians(P.tilt);
  const float across = dot(p - 0.5f, (float2)(-native_sin(a), native_cos(a)));
  const float n = pt_fbm(p * 2.5f, fw * 2.5f, 4, 2.0f, 0.5f, pt_subseed(seed, 1u));
  const float t = across * P.bands + P.warp * 2.5f * n;
  const float wt = fw * (P.bands + P.warp * 2.5f * 2.5f * 2.0f);
  // A 1D fBm along the strata coordinate gives layers of varied width and shade.
  const float s = pt_fbm((float2)(t, 0.37f), wt, 5, 2.0f, 0.6f, pt_subseed(seed, 2u));
  const float v = clamp(0.5f + P.contrast * 1.4f * s, 0.0f, 1.0f);
  float3 c = pt_ramp3(v, P.color_a, P.color_b, P.color_c);
  const float g = pt_octave_weight(80.0f, fw) * pt_vnoise(p * 80.0f, pt_subseed(seed, 3u)) +
                  0.5f * pt_octave_weight(160.0f, fw) * pt_vnoise(p * 160.0f, pt_subseed(seed, 4u));
  c *= 1.0f + 0.25f * P.grain * g;
  return pt_saturate3(c);
}
