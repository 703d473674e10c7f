// @shader "Hexagonal tiles with grout, per-tile variation and an optional second tile colour"
// @param float scale       = 8    [2, 40] log          "Tiles across the texture"
// @param float grout       = 0.06 [0.01, 0.3] log      "Grout width, fraction of a tile"
// @param color tile_color  = (0.75, 0.74, 0.70)        "Main tile colour (linear RGB)"
// @param color alt_color   = (0.10, 0.10, 0.11)        "Second tile colour (linear RGB)"
// @param float alt_fraction = 0.15 [0, 1]              "Fraction of tiles in the second colour"
// @param color grout_color = (0.30, 0.29, 0.27)        "Grout colour (linear RGB)"
// @param float variation   = 0.1  [0, 1]               "Tile-to-tile colour variation"
// @param float bevel       = 0.3  [0, 1]               "Darkening of the rounded tile edges"
// @param float roughness   = 0.2  [0, 1]               "Glaze mottling and dirt"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = p * P.scale;
  const float w = fw * P.scale;
  const float4 h = pt_hex_cell(q);
  const int2 id = pt_hex_id(h.xy);
  const float d = pt_sd_hexagon(h.wz, 0.5f - 0.5f * P.grout);
  const float cover = pt_coverage(d, w);
  const float r0 = pt_rand(id.x, id.y, 0, seed);
  const float3 base = r0 < P.alt_fraction ? P.alt_color : P.tile_color;
  float3 tc = pt_vary_color(base, P.variation, pt_rand(id.x, id.y, 1, seed), pt_rand(id.x, id.y, 2, seed));
  const float n = pt_fbm(q * 1.5f, w * 1.5f, 5, 2.0f, 0.55f, pt_subseed(seed, 3u));
  tc *= 1.0f + P.roughness * 0.5f * n;
  tc *= mix(1.0f, mix(1.0f - 0.6f * P.bevel, 1.0f, smoothstep(0.0f, 0.1f, -d)), pt_detail_weight(0.1f / w));
  const float3 gc = P.grout_color * (1.0f + 0.3f * P.roughness * n);
  return pt_saturate3(mix(gc, tc, cover));
}
