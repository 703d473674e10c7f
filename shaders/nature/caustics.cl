// @shader "Water caustics: bright rippling light network on the bottom of a pool"
// @param float scale       = 5    [1.5, 20] log       "Caustic cells across the texture"
// @param float width       = 0.15 [0.03, 0.5] log     "Width of the bright lines"
// @param float warp        = 0.5  [0, 1]              "Distortion of the network"
// @param float layers      = 0.6  [0, 1]              "Strength of a second, finer network"
// @param float brightness  = 0.8  [0.2, 1]            "Intensity of the light lines"
// @param color water_color = (0.02, 0.18, 0.25)       "Colour of the pool floor in the water (linear RGB)"
// @param color light_color = (0.70, 0.95, 1.00)       "Colour of the caustic light (linear RGB)"

float caustic_layer(float2 q, float w, float width, uint seed) {
  const PtCellular c = pt_cellular(q, 1.0f, seed);
  const float e = 0.5f * (c.f2 - c.f1);  // about the distance to the cell border
  // Bright near the border, fading smoothly inwards; widened by the footprint.
  const float s = width + 0.7f * w;
  const float v = fmax(1.0f - e / s, 0.0f);
  return v * v * (width / s);
}

float3 shade(float2 p, float fw, uint seed, const Params P) {
  float2 q = p * P.scale;
  const float w = fw * P.scale;
  q = pt_warp(q, w, 0.35f * P.warp, 0.8f, 3, pt_subseed(seed, 1u));
  float l = caustic_layer(q, w, P.width, pt_subseed(seed, 2u));
  if (P.layers > 0.0f)
    l += P.layers * 0.6f * caustic_layer(q * 1.9f + 3.7f, w * 1.9f, P.width, pt_subseed(seed, 3u));
  const float n = pt_fbm(p * 2.0f, fw * 2.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 4u));
  const float3 c = P.water_color * (1.0f + 0.3f * n) + P.brightness * l * P.light_color;
  return pt_saturate3(c);
}
