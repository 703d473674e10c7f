// Cell addressing for tilings and scattered features: which tile a point is in, where inside it,
// and the distance to the tile's border (for grout, mortar, gaps antialiased with pt_coverage).

// Voronoi cells with the exact distance to the nearest cell border (two passes, after Inigo
// Quilez), for stones, cobbles, cells and cracks. One feature point per unit cell, displaced by
// jitter in [0, 1].
typedef struct {
  float edge;    // distance to the nearest border between cells (>= 0)
  float f1;      // distance to the cell's feature point
  float2 point;  // the feature point
  int2 cell;     // lattice cell owning the feature point
  float id;      // uniform random number of that cell
} PtVoronoi;

float2 pt_voronoi_point(int cx, int cy, float jitter, uint seed) {
  return (float2)((float)cx, (float)cy) + 0.5f + jitter * (pt_rand2(cx, cy, seed) - 0.5f);
}

PtVoronoi pt_voronoi(float2 p, float jitter, uint seed) {
  const float2 base = floor(p);
  const int bx = (int)base.x, by = (int)base.y;
  PtVoronoi r;
  float best = 1e9f;
  float2 mr = (float2)(0.0f);
  r.cell = (int2)(bx, by);
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const float2 d = pt_voronoi_point(bx + dx, by + dy, jitter, seed) - p;
      const float dd = dot(d, d);
      if (dd < best) { best = dd; mr = d; r.cell = (int2)(bx + dx, by + dy); }
    }
  float edge = 1e9f;
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx) {
      const int cx = r.cell.x + dx, cy = r.cell.y + dy;
      if (dx == 0 && dy == 0) continue;
      const float2 d = pt_voronoi_point(cx, cy, jitter, seed) - p;
      const float2 diff = d - mr;
      const float l2 = dot(diff, diff);
      if (l2 > 1e-10f) edge = fmin(edge, dot(0.5f * (mr + d), diff) * rsqrt(l2));
    }
  r.edge = fmax(edge, 0.0f);
  r.f1 = sqrt(best);
  r.point = p + mr;
  r.id = pt_u01(pt_hash2(r.cell.x, r.cell.y, seed ^ 0x5bd1e995U));
  return r;
}

// Random feature k of lattice cell (cx, cy) for bombing/scattering: .xy a position inside the
// cell, .zw two more uniforms (size, brightness, colour, orientation ...).
float4 pt_cell_feature(int cx, int cy, int k, uint seed) {
  // Two hashes give four 16-bit uniforms: plenty for positions inside a cell.
  const uint h = pt_hash3(cx, cy, k, seed);
  const uint h2 = pt_hash(h ^ 0x9e3779b9U);
  const float s = 1.0f / 65536.0f;
  return (float4)((float)cx + (float)(h & 0xffffU) * s, (float)cy + (float)(h >> 16) * s,
                  (float)(h2 & 0xffffU) * s, (float)(h2 >> 16) * s);
}

// Hexagonal tiling with unit distance between neighbouring centres: rows of hexagons along x with
// flat sides left and right, points at top and bottom. Returns the tile centre .xy and p relative
// to it .zw; pt_sd_hexagon(local.yx, 0.5f) is the distance to the tile border (negative inside).
float4 pt_hex_cell(float2 p) {
  // Two rectangular lattices of centres, offset by half a cell; the nearer centre wins.
  const float2 s = (float2)(1.0f, 1.7320508f);
  const float2 a = floor(p / s + 0.5f) * s;
  const float2 b = floor((p - 0.5f * s) / s + 0.5f) * s + 0.5f * s;
  const float2 da = p - a, db = p - b;
  return dot(da, da) < dot(db, db) ? (float4)(a, da) : (float4)(b, db);
}

// Integer id of a hex tile from its centre (centres lie on a half-integer lattice).
int2 pt_hex_id(float2 centre) { return (int2)((int)floor(centre.x * 2.0f + 0.5f), (int)floor(centre.y / 0.8660254f + 0.5f)); }
