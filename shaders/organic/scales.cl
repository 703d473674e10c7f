// @shader "Scales (fish, reptile, roof shingles): overlapping rounded scales in offset rows"
// @param float scale       = 10   [3, 30] log         "Scales across the texture"
// @param float overlap     = 0.5  [0.2, 0.8]          "How much each row covers the row below"
// @param enum  shape       = round {round, pointed}   "Scale outline"
// @param color color       = (0.20, 0.35, 0.25)       "Scale colour (linear RGB)"
// @param color edge_color  = (0.05, 0.08, 0.06)       "Colour of the scale rims (linear RGB)"
// @param float variation   = 0.25 [0, 1]              "Scale-to-scale colour variation"
// @param float sheen       = 0.4  [0, 1]              "Highlight on each scale"
// @param float rim         = 0.3  [0.05, 0.6]         "Rim width, fraction of a scale"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = p * P.scale;
  const float w = fw * P.scale;
  const float rowh = 1.0f - P.overlap;  // vertical spacing of rows
  const float row0 = pt_floor(q.y / rowh);
  float3 col = P.edge_color;
  // Rows further down are on top; draw from the top row (behind) to the bottom row (front).
  for (int dr = -2; dr <= 1; ++dr) {
    const float row = row0 + (float)dr;
    const float shift = (((int)row) & 1) ? 0.5f : 0.0f;
    const float k0 = pt_floor(q.x - shift);
    for (int dk = 0; dk <= 1; ++dk) {
      const float k = k0 + (float)dk;
      // Scale centre; its visible part hangs below the centre.
      const float2 c = (float2)(k + shift + 0.5f, (row + 1.0f) * rowh);
      float2 d = q - c;
      float sd;
      if (P.shape == SHAPE_POINTED) {
        sd = pt_sd_leaf((float2)(d.x, d.y - 0.1f), 0.62f, 0.5f);
      } else {
        sd = length(d) - 0.55f;
      }
      const float cover = pt_coverage(sd, w);
      if (cover <= 0.0f) continue;
      const int ix = (int)k, iy = (int)row;
      float3 sc = pt_vary_color(P.color, P.variation, pt_rand(ix, iy, 0, seed), pt_rand(ix, iy, 1, seed));
      // Rim darkening and a highlight in the upper middle of the visible part.
      // Rim: a smooth ramp widened by the footprint (filtered when thinner than a pixel).
      const float inner = pt_aa_smoothstep(0.0f, P.rim * 0.55f, -sd, w);
      sc = mix(P.edge_color, sc, inner);
      const float hl = fmax(1.0f - length(d - (float2)(0.0f, 0.15f)) / 0.45f, 0.0f);
      sc *= 1.0f + P.sheen * hl * hl;
      col = mix(col, sc, cover);
    }
  }
  return pt_saturate3(col);
}
