// @shader "Skin: pores, fine wrinkles and blotchy colour variation"
// @param float scale        = 40   [10, 120] log      "Pores across the texture"
// @param float pore_size    = 0.2  [0.05, 0.35]       "Pore radius, fraction of the pore spacing"
// @param float pore_depth   = 0.6  [0.1, 1]             "Darkness of the pores"
// @param float wrinkles     = 0.4  [0, 1]             "Fine criss-cross wrinkles"
// @param float mottle       = 0.4  [0, 1]             "Blotchy colour variation"
// @param color skin_color   = (0.62, 0.40, 0.30)      "Skin colour (linear RGB)"
// @param color blotch_color = (0.60, 0.25, 0.22)      "Colour of the redder blotches (linear RGB)"
// @param color pore_color   = (0.30, 0.16, 0.12)      "Pore colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float m = pt_fbm(p * 4.0f, fw * 4.0f, 5, 2.0f, 0.5f, pt_subseed(seed, 1u));
  float3 c = mix(P.skin_color, P.blotch_color, (0.2f + 0.8f * P.mottle) * smoothstep(-0.2f, 0.5f, m));
  // Wrinkles: two families of ridged lines at an angle to each other.
  const float2 a = (float2)(p.x + 0.3f * p.y, p.y - 0.3f * p.x) * (P.scale * 0.25f);
  const float2 b = (float2)(p.x - 0.5f * p.y, p.y + 0.5f * p.x) * (P.scale * 0.25f);
  const float wa = pt_ridged((float2)(a.x * 0.3f, a.y * 2.0f), fw * P.scale * 0.5f, 3, 2.0f, 0.5f, pt_subseed(seed, 2u));
  const float wb = pt_ridged((float2)(b.x * 2.0f, b.y * 0.3f), fw * P.scale * 0.5f, 3, 2.0f, 0.5f, pt_subseed(seed, 3u));
  const float wr = fmax(pt_aa_threshold(wa, 0.8f, 0.15f, 0.0f), pt_aa_threshold(wb, 0.8f, 0.15f, 0.0f));
  c *= 1.0f - 0.3f * P.wrinkles * wr;
  // Pores: small soft dark dots on a jittered lattice.
  const float2 q = p * P.scale;
  const float w = fw * P.scale;
  // Only points nearer than the largest pore's reach matter (exact 2x2 search up to scale ~45).
  const PtCellular cc = pt_cellular_near(q, 0.8f, 1.4f * P.pore_size + 0.6f * w, pt_subseed(seed, 4u));
  const float r = P.pore_size * (0.6f + 0.8f * cc.id);
  // Pores smaller than a pixel fade to their area-weighted average darkness.
  const float s = r + 0.6f * w;
  const float pore = fmax(1.0f - cc.f1 / s, 0.0f);
  const float dark = P.pore_depth * pore * pore * (r * r) / (s * s) * 1.5f;
  c = mix(c, P.pore_color, clamp(dark, 0.0f, 1.0f));
  return pt_saturate3(c);
}
