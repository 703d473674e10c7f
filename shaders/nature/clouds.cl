// @shader "Clouds: fBm cloud cover over a sky colour, with coverage, edge sharpness and shading"
// @param float scale       = 3    [0.5, 16] log       "Cloud features across the texture"
// @param float coverage    = 0.5  [0.05, 0.95]        "Fraction of the sky covered"
// @param float sharpness   = 0.3  [0, 1]              "Cloud edge sharpness (0: soft haze, 1: crisp puffs)"
// @param float roughness   = 0.5  [0.3, 0.7]         "Amplitude ratio between octaves (detail)"
// @param float stretch     = 1    [1, 4]              "Horizontal elongation of the clouds"
// @param float shading     = 0.3  [0, 1]              "Grey shading of thick cloud cores"
// @param color sky_color   = (0.12, 0.28, 0.65)       "Sky colour (linear RGB)"
// @param color cloud_color = (0.92, 0.92, 0.93)       "Lit cloud colour (linear RGB)"
// @param int   octaves     = 7    [2, 9] fixed        "Noise octaves"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = (float2)(p.x / P.stretch, p.y) * P.scale;
  const float n = pt_fbm(q, fw * P.scale, P.octaves, 2.0f, P.roughness, pt_subseed(seed, 1u));
  // fBm is roughly Gaussian; its CDF makes u roughly uniform so coverage means area fraction.
  const float sd = 0.22f + 0.35f * (P.roughness - 0.5f);
  const float u = pt_normal_cdf(n / sd);
  const float density = clamp((u - (1.0f - P.coverage)) / P.coverage, 0.0f, 1.0f);
  const float k = mix(1.5f, 40.0f, P.sharpness * P.sharpness);
  const float alpha = 1.0f - native_exp(-k * density);
  const float3 cloud = P.cloud_color * (1.0f - 0.55f * P.shading * smoothstep(0.2f, 1.0f, density));
  // A faint haze keeps the sky from being flat even under thin cover.
  const float3 sky = P.sky_color * (1.0f + 0.08f * n);
  return pt_saturate3(mix(sky, cloud, alpha));
}
