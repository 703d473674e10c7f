// @shader "Slate: dark layered stone with cleavage lines, banding and fine texture"
// @param float scale     = 3    [1, 12] log          "Feature size of the layering (features across)"
// @param float stretch   = 4    [1, 12] log          "Elongation of the layers along x"
// @param color color     = (0.10, 0.11, 0.12)        "Main colour (linear RGB)"
// @param color color2    = (0.20, 0.20, 0.19)        "Second tone of the bands (linear RGB)"
// @param float banding   = 0.5  [0.1, 1]               "Contrast between the two tones"
// @param float cleavage  = 0.5  [0, 1]               "Dark cleavage lines along the layers"
// @param float roughness = 0.4  [0, 1]               "Fine surface texture"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = (float2)(p.x / P.stretch, p.y) * P.scale;
  const float w = fw * P.scale;
  const float b = pt_fbm(q, w, 6, 2.0f, 0.5f, pt_subseed(seed, 1u));
  const float t = smoothstep(-0.4f, 0.4f, b * (0.5f + 1.5f * P.banding));
  float3 c = mix(P.color, P.color2, mix(0.5f, t, 0.3f + 0.7f * P.banding));
  // Cleavage: ridged noise squeezed across the layers, thresholded into thin lines.
  const float2 rq = (float2)(q.x * 1.5f, q.y * 6.0f);
  const float r = pt_ridged(rq, w * 6.0f, 4, 2.0f, 0.5f, pt_subseed(seed, 2u));
  const float line = pt_aa_threshold(r, 0.75f, 0.1f, w * 6.0f * 2.0f);
  c *= 1.0f - 0.5f * P.cleavage * line;
  const float f = pt_fbm((float2)(q.x * 8.0f, q.y * 16.0f), w * 16.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 3u));
  c *= 1.0f + 0.4f * P.roughness * f;
  return pt_saturate3(c);
}
