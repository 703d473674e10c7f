// @shader "Marble: turbulent banded veins and branching crack-like veins over a clouded, mottled base"
// @param float veins      = 3     [0.5, 16] log       "Vein bands across the texture"
// @param float angle      = 30    [0, 180]            "Overall vein direction in degrees"
// @param float turbulence = 2.5   [0, 5]              "How strongly turbulence distorts the veins"
// @param float scale      = 3     [1, 8] log         "Feature size of the turbulence (noise frequency)"
// @param float vein_width = 0.15  [0.02, 0.6] log     "Width of the dark veins"
// @param float mottle     = 0.3   [0, 1]              "Fine mottled variation of the base colour"
// @param float network    = 0.3   [0, 1]              "Branching, crack-like veins (0: only the banded veins)"
// @param float clouds     = 0.2   [0, 1]              "Large cloudy patches tinted towards the vein colour"
// @param color base_color = (0.80, 0.78, 0.74)        "Base stone colour (linear RGB)"
// @param color vein_color = (0.18, 0.18, 0.20)        "Vein colour (linear RGB)"
// @param int   octaves    = 6     [1, 8] fixed        "Turbulence octaves"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float a = radians(P.angle);
  const float across = dot(p - 0.5f, (float2)(native_cos(a), native_sin(a)));
  const float t = pt_turbulence(p * P.scale, fw * P.scale, P.octaves, 2.0f, 0.5f, pt_subseed(seed, 1u));
  const float phase = 2.0f * M_PI_F * (P.veins * across + 0.5f * P.turbulence * t);
  // |d phase| per pixel: the linear part plus the turbulence's typical slope.
  const float wv = 2.0f * M_PI_F * fw * (P.veins + 0.6f * P.turbulence * P.scale) ;
  // Box-filter the vein profile along the phase with a few samples once a pixel spans a large
  // part of a vein period; each sample is itself filtered over its share of the footprint.
  const int K = clamp((int)ceil(wv / 0.7f), 1, 8);
  const float step = wv / (float)K;
  float vein = 0.0f;
  for (int k = 0; k < K; ++k) {
    const float ph = phase + step * ((float)k - 0.5f * (float)(K - 1));
    const float v = fabs(native_sin(ph));
    const float v2 = fabs(native_sin(1.7f * ph + 1.3f));
    // A second, thinner family of veins following the same turbulence.
    const float a1 = 1.0f - pt_aa_threshold(v, P.vein_width, 0.8f * P.vein_width, step);
    const float a2 = 0.5f * (1.0f - pt_aa_threshold(v2, 0.35f * P.vein_width, 0.25f * P.vein_width, 1.7f * step));
    vein += fmax(a1, a2);
  }
  vein /= (float)K;
  // Branching veins: the zero set of a turbulence-warped signed noise - a network of thin cracks
  // that fork and rejoin, as in most photographed marble (banded veins alone read as wood-like
  // stripes). Thinner where the noise changes fast; filtered by the noise's slope per pixel.
  const float2 pn = p * P.scale * 1.2f + 0.35f * P.turbulence * (float2)(t, -t);
  const float n = pt_fbm(pn, fw * P.scale * 1.2f, 5, 2.0f, 0.55f, pt_subseed(seed, 3u));
  const float wn = 1.5f * fw * P.scale * 1.2f;
  const float crack = 1.0f - pt_aa_threshold(fabs(n), 0.12f * P.vein_width, 0.08f * P.vein_width, wn);
  vein = fmax(vein * (1.0f - 0.7f * P.network), P.network * crack);
  const float m = pt_fbm(p * P.scale * 0.7f, fw * P.scale * 0.7f, 5, 2.0f, 0.5f, pt_subseed(seed, 2u));
  const float c = pt_fbm(p * P.scale * 0.3f, fw * P.scale * 0.3f, 4, 2.0f, 0.5f, pt_subseed(seed, 4u));
  const float cloud = P.clouds * smoothstep(-0.15f, 0.45f, c);
  const float3 base = mix(P.base_color, 0.4f * P.base_color + 0.6f * P.vein_color, cloud) * (1.0f + P.mottle * 0.35f * m);
  return pt_saturate3(mix(base, P.vein_color, vein));
}
