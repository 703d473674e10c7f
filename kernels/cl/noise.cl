// Lattice noises. Gradients come from a small constant table indexed by a hash: DESIGN.md measured
// this at 8.6 ms per 6-octave 256^2 fBm against 32.7 ms with cos/sin, so no transcendental calls
// stay in the inner loop.

__constant float2 PT_GRADIENTS[32] = {
  (float2)(0.99518473f, 0.09801714f),
  (float2)(0.95694034f, 0.29028468f),
  (float2)(0.88192126f, 0.47139674f),
  (float2)(0.77301045f, 0.63439328f),
  (float2)(0.63439328f, 0.77301045f),
  (float2)(0.47139674f, 0.88192126f),
  (float2)(0.29028468f, 0.95694034f),
  (float2)(0.09801714f, 0.99518473f),
  (float2)(-0.09801714f, 0.99518473f),
  (float2)(-0.29028468f, 0.95694034f),
  (float2)(-0.47139674f, 0.88192126f),
  (float2)(-0.63439328f, 0.77301045f),
  (float2)(-0.77301045f, 0.63439328f),
  (float2)(-0.88192126f, 0.47139674f),
  (float2)(-0.95694034f, 0.29028468f),
  (float2)(-0.99518473f, 0.09801714f),
  (float2)(-0.99518473f, -0.09801714f),
  (float2)(-0.95694034f, -0.29028468f),
  (float2)(-0.88192126f, -0.47139674f),
  (float2)(-0.77301045f, -0.63439328f),
  (float2)(-0.63439328f, -0.77301045f),
  (float2)(-0.47139674f, -0.88192126f),
  (float2)(-0.29028468f, -0.95694034f),
  (float2)(-0.09801714f, -0.99518473f),
  (float2)(0.09801714f, -0.99518473f),
  (float2)(0.29028468f, -0.95694034f),
  (float2)(0.47139674f, -0.88192126f),
  (float2)(0.63439328f, -0.77301045f),
  (float2)(0.77301045f, -0.63439328f),
  (float2)(0.88192126f, -0.47139674f),
  (float2)(0.95694034f, -0.29028468f),
  (float2)(0.99518473f, -0.09801714f)
};

float2 pt_quintic(float2 t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

float pt_grad_dot(int x, int y, uint seed, float2 offset) {
  return dot(PT_GRADIENTS[pt_hash2(x, y, seed) & 31u], offset);
}

// Gradient (Perlin) noise, range about [-1, 1], zero at lattice points, feature size 1.
float pt_gnoise(float2 p, uint seed) {
  const float2 cell = pt_floor(p);
  const float2 f = p - cell;
  const int ix = (int)cell.x;
  const int iy = (int)cell.y;
  const float2 u = pt_quintic(f);
  const float n00 = pt_grad_dot(ix, iy, seed, f);
  const float n10 = pt_grad_dot(ix + 1, iy, seed, f - (float2)(1.0f, 0.0f));
  const float n01 = pt_grad_dot(ix, iy + 1, seed, f - (float2)(0.0f, 1.0f));
  const float n11 = pt_grad_dot(ix + 1, iy + 1, seed, f - (float2)(1.0f, 1.0f));
  // 2D Perlin noise peaks near +-0.7; scale so the practical range is [-1, 1].
  return 1.41421356f * mix(mix(n00, n10, u.x), mix(n01, n11, u.x), u.y);
}

// Two independent gradient noises sharing one lattice hash per corner (the gradients come from
// different bits of it): a 2D vector field for domain warping at about the cost of one noise.
float2 pt_gnoise2(float2 p, uint seed) {
  const float2 cell = pt_floor(p);
  const float2 f = p - cell;
  const int ix = (int)cell.x;
  const int iy = (int)cell.y;
  const float2 u = pt_quintic(f);
  const uint h00 = pt_hash2(ix, iy, seed), h10 = pt_hash2(ix + 1, iy, seed);
  const uint h01 = pt_hash2(ix, iy + 1, seed), h11 = pt_hash2(ix + 1, iy + 1, seed);
  const float2 f10 = f - (float2)(1.0f, 0.0f), f01 = f - (float2)(0.0f, 1.0f), f11 = f - (float2)(1.0f, 1.0f);
  const float2 n00 = (float2)(dot(PT_GRADIENTS[h00 & 31u], f), dot(PT_GRADIENTS[(h00 >> 8) & 31u], f));
  const float2 n10 = (float2)(dot(PT_GRADIENTS[h10 & 31u], f10), dot(PT_GRADIENTS[(h10 >> 8) & 31u], f10));
  const float2 n01 = (float2)(dot(PT_GRADIENTS[h01 & 31u], f01), dot(PT_GRADIENTS[(h01 >> 8) & 31u], f01));
  const float2 n11 = (float2)(dot(PT_GRADIENTS[h11 & 31u], f11), dot(PT_GRADIENTS[(h11 >> 8) & 31u], f11));
  return 1.41421356f * mix(mix(n00, n10, u.x), mix(n01, n11, u.x), u.y);
}

// Value noise: random values at lattice points, smoothly interpolated; range [-1, 1].
float pt_vnoise(float2 p, uint seed) {
  const float2 cell = pt_floor(p);
  const float2 f = p - cell;
  const int ix = (int)cell.x;
  const int iy = (int)cell.y;
  const float2 u = pt_quintic(f);
  const float v00 = pt_u01(pt_hash2(ix, iy, seed));
  const float v10 = pt_u01(pt_hash2(ix + 1, iy, seed));
  const float v01 = pt_u01(pt_hash2(ix, iy + 1, seed));
  const float v11 = pt_u01(pt_hash2(ix + 1, iy + 1, seed));
  return 2.0f * mix(mix(v00, v10, u.x), mix(v01, v11, u.x), u.y) - 1.0f;
}

// Feature point of lattice cell (cx, cy) for cellular noise and Voronoi cells. `mixed` is
// pt_hash(seed), hashed once per lookup: one hash per point (two 16-bit coordinates) instead of
// pt_rand2's chain of four keeps the 9 points of a lookup cheap (pt_cellular 11-14% faster in
// caustics, crinkled, cracked_mud; A/B with bench_render --ab).
float2 pt_voronoi_point(int cx, int cy, float jitter, uint mixed) {
  const uint h = pt_hash(((uint)cx * 0x8da6b343U) ^ ((uint)cy * 0xd8163841U) ^ mixed);
  const float2 u = (float2)((float)(h & 0xffffU), (float)(h >> 16)) * (1.0f / 65536.0f);
  return (float2)((float)cx, (float)cy) + 0.5f + jitter * (u - 0.5f);
}

// Cellular (Worley) noise: one feature point per unit cell, displaced by `jitter` in [0, 1].
// f1/f2 are the distances to the nearest and second nearest points; cell/point identify the
// nearest one (for colouring stones per cell) and id is a uniform random number of that cell.
typedef struct {
  float f1;
  float f2;
  int2 cell;
  float2 point;
  float id;
} PtCellular;

PtCellular pt_cellular(float2 p, float jitter, uint seed) {
  const float2 base = pt_floor(p);
  const int bx = (int)base.x;
  const int by = (int)base.y;
  const uint mixed = pt_hash(seed);
  PtCellular r;
  float d1 = 1e9f, d2 = 1e9f;  // squared distances: one sqrt per result, not per point
  r.cell = (int2)(bx, by);
  r.point = base;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const int cx = bx + dx;
      const int cy = by + dy;
      const float2 pt = pt_voronoi_point(cx, cy, jitter, mixed);
      const float2 d = pt - p;
      const float dd = dot(d, d);
      if (dd < d1) {
        d2 = d1;
        d1 = dd;
        r.cell = (int2)(cx, cy);
        r.point = pt;
      } else if (dd < d2) {
        d2 = dd;
      }
    }
  }
  r.f1 = sqrt(d1);
  r.f2 = sqrt(d2);
  r.id = pt_u01(pt_hash2(r.cell.x, r.cell.y, seed ^ 0x5bd1e995U));
  return r;
}

// The nearest point of pt_cellular (the same points, cell, point and id) for patterns where only
// points closer than `radius` matter (dots, pits, pores): f1 is exact when below radius, else
// some value >= radius; f2 is not computed (1e9). Points within radius of p all lie in the 2x2
// cells nearest p when radius <= 1 - jitter / 2, so that case checks 4 cells instead of 9.
PtCellular pt_cellular_near(float2 p, float jitter, float radius, uint seed) {
  const int n = radius <= 1.0f - 0.5f * jitter ? 2 : 3;
  const int x0 = n == 2 ? (int)pt_floor(p.x - 0.5f) : (int)pt_floor(p.x) - 1;
  const int y0 = n == 2 ? (int)pt_floor(p.y - 0.5f) : (int)pt_floor(p.y) - 1;
  const uint mixed = pt_hash(seed);
  PtCellular r;
  float d1 = 1e9f;
  r.cell = (int2)(x0, y0);
  r.point = p;
  for (int dy = 0; dy < n; ++dy) {
    for (int dx = 0; dx < n; ++dx) {
      const int cx = x0 + dx;
      const int cy = y0 + dy;
      const float2 pt = pt_voronoi_point(cx, cy, jitter, mixed);
      const float2 d = pt - p;
      const float dd = dot(d, d);
      if (dd < d1) {
        d1 = dd;
        r.cell = (int2)(cx, cy);
        r.point = pt;
      }
    }
  }
  r.f1 = sqrt(d1);
  r.f2 = 1e9f;
  r.id = pt_u01(pt_hash2(r.cell.x, r.cell.y, seed ^ 0x5bd1e995U));
  return r;
}

float pt_cellular_f1(float2 p, float jitter, uint seed) { return pt_cellular(p, jitter, seed).f1; }
float pt_cellular_f2(float2 p, float jitter, uint seed) { return pt_cellular(p, jitter, seed).f2; }
float pt_cellular_f2_minus_f1(float2 p, float jitter, uint seed) {
  const PtCellular c = pt_cellular(p, jitter, seed);
  return c.f2 - c.f1;
}
