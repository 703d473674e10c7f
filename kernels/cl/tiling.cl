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

// Feature point of lattice cell (cx, cy). `mixed` is pt_hash(seed), hashed once per lookup: one
// hash per point (two 16-bit coordinates) keeps the 34 points of pt_voronoi cheap.
float2 pt_voronoi_point(int cx, int cy, float jitter, uint mixed) {
  const uint h = pt_hash(((uint)cx * 0x8da6b343U) ^ ((uint)cy * 0xd8163841U) ^ mixed);
  const float2 u = (float2)((float)(h & 0xffffU), (float)(h >> 16)) * (1.0f / 65536.0f);
  return (float2)((float)cx, (float)cy) + 0.5f + jitter * (u - 0.5f);
}

PtVoronoi pt_voronoi(float2 p, float jitter, uint seed) {
  const float2 base = floor(p);
  const int bx = (int)base.x, by = (int)base.y;
  const uint mixed = pt_hash(seed);
  PtVoronoi r;
  float best = 1e9f;
  float2 mr = (float2)(0.0f);
  r.cell = (int2)(bx, by);
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const float2 d = pt_voronoi_point(bx + dx, by + dy, jitter, mixed) - p;
      const float dd = dot(d, d);
      if (dd < best) { best = dd; mr = d; r.cell = (int2)(bx + dx, by + dy); }
    }
  float edge = 1e9f;
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx) {
      const int cx = r.cell.x + dx, cy = r.cell.y + dy;
      if (dx == 0 && dy == 0) continue;
      const float2 d = pt_voronoi_point(cx, cy, jitter, mixed) - p;
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

// Axis-aligned herringbone of 2 x 1 bricks (units: the brick width). Horizontal bricks have
// lower-left corners (k - 2m, k + 2m), vertical ones (k - 2m + 2, k + 2m - 1): staircases along
// the diagonal, repeated every (-2, 2). Returns the brick centre .xy and p relative to it .zw;
// *vertical tells the orientation and *id is a unique integer pair of the brick.
float4 pt_herringbone(float2 p, int* vertical, int2* id) {
  const int k0 = (int)floor(0.5f * (p.x + p.y));
  const int m0 = (int)floor(0.25f * (p.y - p.x));
  float4 best = (float4)(0.0f, 0.0f, 1e9f, 1e9f);
  float best_d = 1e9f;
  *vertical = 0;
  *id = (int2)(k0, m0);
  for (int dk = -2; dk <= 1; ++dk)
    for (int dm = -1; dm <= 1; ++dm) {
      const int k = k0 + dk, m = m0 + dm;
      for (int v = 0; v <= 1; ++v) {
        const float2 corner = v ? (float2)((float)(k - 2 * m + 2), (float)(k + 2 * m - 1))
                                : (float2)((float)(k - 2 * m), (float)(k + 2 * m));
        const float2 half_size = v ? (float2)(0.5f, 1.0f) : (float2)(1.0f, 0.5f);
        const float2 c = corner + half_size;
        const float2 d = fabs(p - c) - half_size;
        const float outside = fmax(d.x, d.y);  // <= 0 inside
        if (outside < best_d) {
          best_d = outside;
          best = (float4)(c, p - c);
          *vertical = v;
          *id = (int2)(k, m);
        }
      }
    }
  return best;
}
