// @shader "Organic cells: tissue-like Voronoi cells with walls, shaded cytoplasm and nuclei"
// @param float scale         = 8    [2, 30] log       "Cells across the texture"
// @param float jitter        = 0.85 [0, 1]            "Irregularity of the cell layout"
// @param float wall          = 0.08 [0.01, 0.4] log   "Cell wall thickness, fraction of a cell"
// @param float nucleus       = 0.18 [0, 0.35]         "Nucleus radius, fraction of a cell (0: none)"
// @param color cell_color    = (0.75, 0.45, 0.50)     "Cytoplasm colour (linear RGB)"
// @param color wall_color    = (0.30, 0.08, 0.15)     "Cell wall colour (linear RGB)"
// @param color nucleus_color = (0.20, 0.05, 0.25)     "Nucleus colour (linear RGB)"
// @param float variation     = 0.2  [0, 1]            "Cell-to-cell colour variation"
// @param float shading       = 0.4  [0, 1]            "Darkening of the cytoplasm towards the wall"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  float2 q = p * P.scale;
  const float w = fw * P.scale;
  q = pt_warp(q, w, 0.12f, 1.5f, 2, pt_subseed(seed, 1u));
  const PtVoronoi v = pt_voronoi(q, P.jitter, seed);
  const float d = 0.5f * P.wall - v.edge;
  const float inside = pt_coverage(d, w);
  float3 c = pt_vary_color(P.cell_color, P.variation, v.id, pt_rand(v.cell.x, v.cell.y, 1, seed));
  c *= mix(1.0f, mix(1.0f - 0.5f * P.shading, 1.0f, smoothstep(0.0f, 0.3f, -d)), pt_detail_weight(0.3f / w));
  // Nucleus: a slightly off-centre blob with a wobbly outline.
  const float2 off = 0.15f * (pt_rand2(v.cell.x, v.cell.y, seed ^ 77u) - 0.5f);
  const float nn = pt_gnoise((q - v.point) * 6.0f + v.id * 10.0f, pt_subseed(seed, 2u));
  const float dn = length(q - v.point - off) - P.nucleus * (1.0f + 0.15f * nn);
  const float nuc = P.nucleus > 0.0f ? pt_coverage(dn, w) : 0.0f;
  c = mix(c, P.nucleus_color, nuc);
  const float n = pt_fbm(q * 3.0f, w * 3.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 3u));
  c *= 1.0f + 0.15f * n;
  return pt_saturate3(mix(P.wall_color * (1.0f + 0.2f * n), c, inside));
}
