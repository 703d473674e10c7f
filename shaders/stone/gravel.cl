// @shader "Gravel: packed angular or rounded pebbles, lit from one side, with dark gaps"
// @param float scale       = 28   [6, 60] log         "Pebbles across the texture"
// @param float gap         = 0.2  [0.02, 0.6] log     "Dark gaps between pebbles, fraction of a pebble"
// @param float angularity  = 0.6  [0, 1]              "0 rounded pebbles, 1 crushed angular stone"
// @param float lighting    = 0.8  [0, 1]              "Strength of the side lighting (relief)"
// @param color stone_color = (0.30, 0.30, 0.30)       "Mean pebble colour (linear RGB)"
// @param float gap_shade   = 0.15 [0, 0.6]             "Shadow between pebbles, fraction of the pebble colour (always darker)"
// @param float variation   = 0.6  [0, 1]              "Pebble-to-pebble brightness and tint variation"
// @param float roughness   = 0.3  [0, 1]              "Surface speckle"

// Height of the stone surface at q (0 in the gaps, up to 1 on a stone) and the stone's Voronoi
// cell. Each stone gets its own size (crushed stone packs unevenly: some gaps are wide and show
// the stones below) and a dome (rounded) or a pyramid of flat facets (angular).
typedef struct {
  PtVoronoi v;
  float inner;   // distance inside the stone (negative in the gap)
  float height;
} GravelStone;

GravelStone gravel_stone(float2 q, uint seed, const Params P) {
  GravelStone s;
  s.v = pt_voronoi(q, 1.0f, seed);
  const float gap = P.gap * (0.3f + 2.0f * pt_rand(s.v.cell.x, s.v.cell.y, 4, seed));
  s.inner = s.v.edge - 0.5f * gap;
  const float h = clamp(s.inner / fmax(s.inner + s.v.f1, 1e-4f) * 2.0f, 0.0f, 1.0f);
  s.height = mix(sqrt(h), h, P.angularity);
  return s;
}

// Brightness of a stone under light from the top left: a dome leans away from the stone's
// centre; an angular stone is cut into flat facets (a finer Voronoi inside the stone), each tilted
// its own way - what makes crushed stone read as crushed: bright and dark faces side by side.
float gravel_light(float2 q, const GravelStone st, uint seed, const Params P) {
  const float2 light_dir = (float2)(-0.7071f, -0.7071f);
  const float2 radial = (q - st.v.point) / fmax(st.v.f1 + fmax(st.inner, 0.0f), 1e-4f);
  const PtVoronoi facet = pt_voronoi(q * 2.3f, 1.0f, pt_subseed(seed, 3u));
  const float fa = 6.2831853f * pt_rand(facet.cell.x, facet.cell.y, 5, seed);
  const float2 facet_tilt = 0.5f * (radial + (float2)(cos(fa), sin(fa)));
  const float2 tilt = mix(radial, facet_tilt, P.angularity) * (1.0f - 0.5f * st.height);
  const float ra = pt_rand(st.v.cell.x, st.v.cell.y, 2, seed);
  return 1.0f + P.lighting * (1.3f * dot(tilt, light_dir) + 0.3f * (st.height - 0.5f) + 0.2f * (ra - 0.5f));
}

float3 shade(float2 p, float fw, uint seed, const Params P) {
  float2 q = p * P.scale;
  const float w = fw * P.scale;
  q = pt_warp(q, w, 0.15f, 1.0f, 2, pt_subseed(seed, 1u));
  const float2 light_dir = (float2)(-0.7071f, -0.7071f);
  const GravelStone st = gravel_stone(q, seed, P);
  const float cover = pt_coverage(-st.inner, w);
  // Cast shadow: a stone nearer the light that stands higher than this point darkens it.
  const GravelStone up = gravel_stone(q - 0.35f * light_dir, seed, P);
  const float shadow = clamp((up.height - st.height) * 2.0f, 0.0f, 1.0f) *
                       (float)(up.v.cell.x != st.v.cell.x || up.v.cell.y != st.v.cell.y);
  const float detail = pt_detail_weight(0.5f / w);
  float light = mix(1.0f, gravel_light(q, st, seed, P) * (1.0f - 0.6f * P.lighting * shadow), detail);
  float3 sc = pt_vary_color(P.stone_color, P.variation, st.v.id, pt_rand(st.v.cell.x, st.v.cell.y, 3, seed));
  const float n = pt_fbm(q * 3.0f, w * 3.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 2u));
  sc *= fmax(light, 0.05f) * (1.0f + P.roughness * 0.5f * n);
  // A faint sheen on the facets facing the light, whatever the stone's colour (dark stone still
  // shows its stones); per stone where the facets are below a pixel.
  const float ra_sheen = pt_rand(st.v.cell.x, st.v.cell.y, 2, seed);
  sc += 0.03f * P.lighting * mix(ra_sheen, fmax(light - 1.0f, 0.0f), detail);
  sc *= mix(0.6f, 1.0f, pt_aa_smoothstep(0.0f, 0.12f, st.inner, w));  // a soft rim
  // The wide gaps show a lower layer of stones, in the gap colour's shadow.
  const uint lower_seed = pt_subseed(seed, 4u);
  const float2 ql = q * 1.15f + (float2)(17.3f, 9.1f);
  const GravelStone low = gravel_stone(ql, lower_seed, P);
  float3 lc = pt_vary_color(P.stone_color, P.variation, low.v.id, pt_rand(low.v.cell.x, low.v.cell.y, 3, lower_seed));
  lc *= fmax(mix(1.0f, gravel_light(ql, low, lower_seed, P), detail), 0.05f);
  // The gap is the stones' shadow, never brighter than them: a free gap colour let the search
  // turn gravel into a mosaic with white grout that matches a photo's colour statistics.
  const float3 gap_color = P.stone_color * P.gap_shade;
  const float3 below = mix(gap_color, 0.5f * (lc + gap_color), pt_coverage(-low.inner, w));
  return pt_saturate3(mix(below * (1.0f - 0.5f * shadow), sc, cover));
}
