// @shader "Sand: fine grain with optional wind ripples"
// @param float ripples      = 12   [2, 40] log        "Ripples across the texture"
// @param float ripple_depth = 0.5  [0, 1]             "Strength of the ripple shading (0: flat sand)"
// @param float warp         = 0.5  [0, 1]             "Waviness of the ripples"
// @param float grain        = 0.5  [0, 1]             "Contrast of the individual grains"
// @param float grain_size   = 3    [1.5, 6] log       "Grain size in 1/256ths of the texture"
// @param color color        = (0.62, 0.50, 0.33)      "Sand colour (linear RGB)"
// @param color shadow_color = (0.40, 0.30, 0.18)      "Colour of the ripple flanks (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float n = pt_fbm(p * 2.0f, fw * 2.0f, 4, 2.0f, 0.5f, pt_subseed(seed, 1u));
  const float t = p.y * P.ripples + P.warp * 2.0f * n + 0.3f * P.warp * p.x * P.ripples * n;
  const float wt = fw * P.ripples * (1.0f + 2.0f * P.warp);
  // Asymmetric ripple: a long gentle windward slope and a short steep lee face (shadow).
  const float lee = pt_soft_pulsetrain(0.3f, t, wt, 0.25f);
  float3 c = mix(P.color, P.shadow_color, P.ripple_depth * lee);
  const float f = 256.0f / P.grain_size;
  const float g = pt_octave_weight(f, fw) * pt_vnoise(p * f, pt_subseed(seed, 2u)) +
                  0.5f * pt_octave_weight(2.0f * f, fw) * pt_vnoise(p * 2.0f * f, pt_subseed(seed, 3u));
  c *= 1.0f + 0.5f * P.grain * g + 0.1f * n;
  return pt_saturate3(c);
}
