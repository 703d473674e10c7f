// Cell addressing for tilings and scattered features: which tile a point is in, where inside it,
// and the distance to the tile's border (for grout, mortar, gaps antialiased with pt_coverage).

// Voronoi cells with the distance to the nearest cell border, for stones, cobbles, cells and
// cracks. One feature point per unit cell, displaced by jitter in [0, 1].
typedef struct {
  float edge;    // distance to the nearest border between cells (>= 0)
  float f1;      // distance to the cell's feature point
  float2 point;  // the feature point
  int2 cell;     // lattice cell owning the feature point
  float id;      // uniform random number of that cell
} PtVoronoi;

// One pass over the 3x3 cells around p keeps the three nearest points; the border distance is the
// distance to the nearer of the bisectors between the nearest point and the second and third.
// Near a border (where the value matters: gaps, cracks, rims) the cell across it is practically
// always one of those two, so the result there equals the exact two-pass search (5x5 second pass,
// after Inigo Quilez); further inside a cell it can come out slightly larger. Measured 19-25% faster for cells, stones
// and cracked_mud (A/B, bench_render --ab), with 1-2% of pixels changing, by at most 0.09 (0-1).
PtVoronoi pt_voronoi(float2 p, float jitter, uint seed) {
  const float2 base = pt_floor(p);
  const int bx = (int)base.x, by = (int)base.y;
  const uint mixed = pt_hash(seed);
  float d1 = 1e9f, d2 = 1e9f, d3 = 1e9f;  // squared distances, nearest first
  float2 v1 = (float2)(0.0f), v2 = (float2)(0.0f), v3 = (float2)(0.0f);
  int2 c1 = (int2)(bx, by);
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const float2 d = pt_voronoi_point(bx + dx, by + dy, jitter, mixed) - p;
      const float dd = dot(d, d);
      // Branches, not selects: measured faster (most points are rejected by the first test).
      if (dd < d3) {
        if (dd < d2) {
          d3 = d2;
          v3 = v2;
          if (dd < d1) {
            d2 = d1;
            v2 = v1;
            d1 = dd;
            v1 = d;
            c1 = (int2)(bx + dx, by + dy);
          } else {
            d2 = dd;
            v2 = d;
          }
        } else {
          d3 = dd;
          v3 = d;
        }
      }
    }
  const float2 e2 = v2 - v1, e3 = v3 - v1;
  const float l2 = dot(e2, e2), l3 = dot(e3, e3);
  float edge = 1e9f;
  if (l2 > 1e-10f) edge = dot(0.5f * (v1 + v2), e2) * rsqrt(l2);
  if (l3 > 1e-10f) edge = fmin(edge, dot(0.5f * (v1 + v3), e3) * rsqrt(l3));
  PtVoronoi r;
  r.edge = fmax(edge, 0.0f);
  r.f1 = sqrt(d1);
  r.point = p + v1;
  r.cell = c1;
  r.id = pt_u01(pt_hash2(c1.x, c1.y, seed ^ 0x5bd1e995U));
  return r;
}

// Random feature k of lattice cell (cx, cy) for bombing/scattering: .xy a position inside the
// cell, .zw two more uniforms (size, brightness, colour, orientation ...).
float4 pt_cell_feature(int cx, int cy, int k, uint seed) {
  // Two hashes give four 16-bit uniforms: plenty for positions inside a cell. The first mixes the
  // cell, k and the seed in one hash (as pt_voronoi_point does) instead of pt_hash3's chain of
  // four: grass, which reads 27 features per pixel, rendered 15% faster (A/B, bench_render --ab).
  const uint h = pt_hash(((uint)cx * 0x8da6b343U) ^ ((uint)cy * 0xd8163841U) ^ ((uint)k * 0xcb1ab31fU) ^ pt_hash(seed));
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
  const float2 a = pt_floor(p / s + 0.5f) * s;
  const float2 b = pt_floor((p - 0.5f * s) / s + 0.5f) * s + 0.5f * s;
  const float2 da = p - a, db = p - b;
  return dot(da, da) < dot(db, db) ? (float4)(a, da) : (float4)(b, db);
}

// Integer id of a hex tile from its centre (centres lie on a half-integer lattice).
int2 pt_hex_id(float2 centre) { return (int2)((int)pt_floor(centre.x * 2.0f + 0.5f), (int)pt_floor(centre.y / 0.8660254f + 0.5f)); }

// Axis-aligned herringbone of 2 x 1 bricks (units: the brick width). Horizontal bricks have
// lower-left corners (k - 2m, k + 2m), vertical ones (k - 2m + 2, k + 2m - 1): staircases along
// the diagonal, repeated every (-2, 2). Returns the brick centre .xy and p relative to it .zw;
// *vertical tells the orientation and *id is a unique integer pair of the brick.
float4 pt_herringbone(float2 p, int* vertical, int2* id) {
  const int k0 = (int)pt_floor(0.5f * (p.x + p.y));
  const int m0 = (int)pt_floor(0.25f * (p.y - p.x));
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
