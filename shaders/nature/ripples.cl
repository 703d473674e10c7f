// @shader "Water surface: wind ripples and small waves with sky reflection and glints"
// @param float scale        = 6    [1.5, 30] log      "Waves across the texture"
// @param float stretch      = 2    [1, 6]             "Elongation of the waves across the wind"
// @param float choppiness   = 0.5  [0, 1]             "Sharp crests (0: smooth swell)"
// @param color deep_color   = (0.01, 0.06, 0.10)      "Colour of the water facing the viewer (linear RGB)"
// @param color sky_color    = (0.45, 0.60, 0.75)      "Reflected sky colour on slopes facing away (linear RGB)"
// @param float glints       = 0.4  [0, 1]             "Bright sun glints on the crests"
// @param float detail       = 0.5  [0, 1]             "Small ripples on the waves"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = (float2)(p.x / P.stretch, p.y) * P.scale;
  const float w = fw * P.scale;
  // Height: ridged noise gives sharp crests, fBm a smooth swell; the mix is the choppiness.
  const float r = pt_ridged(q, w, 4, 2.0f, 0.5f, pt_subseed(seed, 1u));
  const float s = 0.5f + 0.5f * pt_fbm(q, w, 4, 2.0f, 0.5f, pt_subseed(seed, 2u));
  float h = mix(s, r, P.choppiness);
  h += P.detail * 0.25f * pt_fbm(q * 4.0f + 2.3f, w * 4.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 3u));
  // Reflection: higher parts (crests, slopes towards the horizon) reflect more sky (Fresnel-ish).
  const float refl = clamp(h * 1.1f - 0.1f, 0.0f, 1.0f);
  float3 c = mix(P.deep_color, P.sky_color, refl * refl);
  const float g = pt_aa_threshold(h, 0.82f, 0.06f, w * 3.0f);
  c += P.glints * g * (float3)(1.0f, 0.97f, 0.9f);
  return pt_saturate3(c);
}
