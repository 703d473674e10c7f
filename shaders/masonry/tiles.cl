// @shader "Square tiles with grout lines, per-tile colour variation, bevelled edges and glaze mottling"
// @param int   tiles       = 6    [2, 32]            "Tiles along each side of the texture"
// @param float grout       = 0.06 [0.01, 0.4] log    "Grout width, fraction of a tile"
// @param color tile_color  = (0.70, 0.67, 0.60)      "Mean tile colour (linear RGB)"
// @param color grout_color = (0.22, 0.21, 0.19)      "Grout colour (linear RGB)"
// @param float variation   = 0.15 [0, 1]             "Tile-to-tile colour variation"
// @param float bevel       = 0.4  [0, 1]             "Darkening of the rounded tile edges"
// @param float corner      = 0.08 [0, 0.5]           "Corner radius, fraction of a tile"
// @param float roughness   = 0.2  [0, 1]             "Glaze mottling and dirt"
// @param bool  offset      = false                   "Offset every other row by half a tile"
// @param float grain       = 0    [0, 1]             "Stains and grain of the tile faces at every scale down to the pixel"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float n_tiles = (float)P.tiles;
  const float2 q = p * n_tiles;
  const float w = fw * n_tiles;
  const float4 c = pt_brick_cell(q, 1.0f, P.offset ? 0.5f : 0.0f);
  const int cx = (int)c.x, cy = (int)c.y;
  const float2 lp = c.zw - 0.5f;
  const float h = 0.5f - 0.5f * P.grout;
  const float d = pt_sd_round_box(lp, (float2)(h), P.corner * h);
  const float cover = pt_coverage(d, w);

  float3 tc = pt_vary_color(P.tile_color, P.variation, pt_rand(cx, cy, 0, seed), pt_rand(cx, cy, 1, seed));
  const float n = pt_fbm(q * 1.5f, w * 1.5f, 6, 2.0f, 0.55f, pt_subseed(seed, 3u));
  tc *= 1.0f + P.roughness * 0.5f * n;
  // Grain at every scale down to the pixel, as photographed stone and ceramic show. Without it
  // only many small tiles put a photo's fine detail into a render: matches of tile photos came
  // back 3-6x too small (session 18). Default 0: earlier specs render as they did.
  if (P.grain > 0.0f)  // the default 0 renders as before the parameter existed, at its cost
    tc *= 1.0f + P.grain * 1.2f * pt_fbm(q * 3.0f, w * 3.0f, 8, 2.0f, 0.75f, pt_subseed(seed, 5u));
  // Bevel: the face darkens over the outer tenth of the tile.
  const float rim = smoothstep(0.0f, 0.1f, -d);
  tc *= mix(1.0f, mix(1.0f - 0.6f * P.bevel, 1.0f, rim), pt_detail_weight(0.1f / w));

  const float3 gc = P.grout_color * (1.0f + 0.3f * P.roughness * n);
  return pt_saturate3(mix(gc, tc, cover));
}
