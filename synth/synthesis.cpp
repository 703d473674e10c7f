#include "synth/synthesis.h"
#include "synth/plane.h"
#include "synth/timing.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include <fmt/format.h>

#include "core/error.h"
#include "kernels/buffers.h"
#include "kernels/runtime.h"

namespace proctex::synth {
namespace {

// Integer-only kernels: coordinates, hashes and distances are exact on every device.
const char* kSource = R"CL(
uint sy_hash(uint x) {
  x ^= x >> 16; x *= 0x7feb352dU; x ^= x >> 15; x *= 0x846ca68bU; x ^= x >> 16;
  return x;
}
uint sy_hash_pos(long x, long y, uint level, uint seed, uint lane) {
  const ulong ux = (ulong)x, uy = (ulong)y;
  uint h = sy_hash(seed ^ sy_hash(level * 0x9e3779b9U + lane * 0x85ebca6bU + 0x632be5abU));
  h = sy_hash(h ^ (uint)ux);
  h = sy_hash(h ^ (uint)(ux >> 32) ^ 0x27d4eb2fU);
  h = sy_hash(h ^ (uint)uy ^ 0x165667b1U);
  h = sy_hash(h ^ (uint)(uy >> 32) ^ 0xd3a2646cU);
  return h;
}
int sy_wrap(int x, int n) { int r = x % n; return r < 0 ? r + n : r; }
int sy_reflect(int x, int n) { const int p = 2 * n - 2; x = sy_wrap(x, p); return x >= n ? p - x : x; }
long sy_wrapl(long x, long n) { long r = x % n; return r < 0 ? r + n : r; }
int sy_step(int x, int n) { return x < 0 ? x + n : (x >= n ? x - n : x); }  // |x| < 2n only
// Whether the 8 neighbours q[+-1], q[+-w +- 1] of a pixel at exemplar position s0 all continue its
// patch, i.e. neighbour d holds s0 + h d (wrapped on a torus; h at most the exemplar's side): the
// three expected columns and rows are computed once and each neighbour is one 64-bit comparison.
int sy_inside(global const int2* q, int w, int2 s0, int h, int ew, int eh, int toroidal) {
  int xm = s0.x - h, xp = s0.x + h, ym = s0.y - h, yp = s0.y + h;
  if (toroidal) { xm = sy_step(xm, ew); xp = sy_step(xp, ew); ym = sy_step(ym, eh); yp = sy_step(yp, eh); }
  const long a = as_long((int2)(xm, ym)), b = as_long((int2)(s0.x, ym)), c = as_long((int2)(xp, ym));
  const long d = as_long((int2)(xm, s0.y)), e = as_long((int2)(xp, s0.y));
  const long f = as_long((int2)(xm, yp)), g = as_long((int2)(s0.x, yp)), k = as_long((int2)(xp, yp));
  global const long* r = (global const long*)q;
  return (r[-w - 1] == a) & (r[-w] == b) & (r[-w + 1] == c) & (r[-1] == d) & (r[1] == e) & (r[w - 1] == f) &
         (r[w] == g) & (r[w + 1] == k);
}

// S_l[q] = S_{l-1}[q / 2] + floor(h_l (d - 1/2)) + J_l(q),  J = floor(h_l r_l H(q) + 1/2).
kernel void sy_upsample(global const int2* parent, int pw, long pox, long poy, int parent_zero,
                     global int2* S, int w, int h, long ox, long oy,
                     int spacing, int ew, int eh, long period_x, long period_y,
                     int rq, uint seed, uint level, global const uchar* jmap, int jw, int jh, int shift,
                     global const long* pastes, int paste_count, global const int* shifts, int shift_count,
                     int shift_prob) {
  const int i = get_global_id(0), j = get_global_id(1);
  if (i >= w || j >= h) return;
  const long qx = ox + i, qy = oy + j;
  int2 s = (int2)(0, 0);
  if (!parent_zero) s = parent[(long)((qy >> 1) - poy) * pw + ((qx >> 1) - pox)];
  const int offx = (qx & 1) ? spacing / 2 : -((spacing + 1) / 2);
  const int offy = (qy & 1) ? spacing / 2 : -((spacing + 1) / 2);
  const long hx = period_x > 0 ? sy_wrapl(qx, period_x) : qx;
  const long hy = period_y > 0 ? sy_wrapl(qy, period_y) : qy;
  long jx = 0, jy = 0;
  // The jitter map scales r at the finest-level pixel this one covers; it repeats over the plane.
  // (jw = 0: no map, 255 everywhere, without the two 64-bit modulos per pixel.)
  const int scaled =
      jw == 0 ? rq : (int)(((long)rq * jmap[sy_wrapl(qy << shift, jh) * jw + sy_wrapl(qx << shift, jw)]) / 255);
  if (scaled > 0 && shift_count > 0) {
    // One of the exemplar's most self-similar translations (structure-keeping layout jitter); below
    // the first level only with probability shift_prob / 65536 (breaking up large pieces).
    if (shift_prob >= 65536 || (int)(sy_hash_pos(hx, hy, level, seed, 3) & 0xffffU) < shift_prob) {
      const uint k = sy_hash_pos(hx, hy, level, seed, 2) % (uint)shift_count;
      jx = shifts[2 * k];
      jy = shifts[2 * k + 1];
    }
  } else if (scaled > 0) {
    const int Hx = (int)(sy_hash_pos(hx, hy, level, seed, 0) % 131073U) - 65536;
    const int Hy = (int)(sy_hash_pos(hx, hy, level, seed, 1) % 131073U) - 65536;
    jx = ((long)spacing * scaled * Hx + (1L << 31)) >> 32;
    jy = ((long)spacing * scaled * Hy + (1L << 31)) >> 32;
  }
  int2 out = (int2)(sy_wrap(s.x + offx + (int)jx, ew), sy_wrap(s.y + offy + (int)jy, eh));
  // Pasted features: {out_x, out_y, width, height, offset_x, offset_y} on the finest grid.
  const long fx = qx << shift, fy = qy << shift;
  for (int k = 0; k < paste_count; ++k) {
    global const long* pp = pastes + 6 * k;
    if (fx >= pp[0] && fx < pp[0] + pp[2] && fy >= pp[1] && fy < pp[1] + pp[3])
      out = (int2)((int)sy_wrapl(fx + pp[4], ew), (int)sy_wrapl(fy + pp[5], eh));
  }
  S[(long)j * w + i] = out;
}

// One correction sub-pass: the pixels whose absolute coordinates have parity (parx, pary). The
// other classes are read only, so the update in place is race-free and order-independent.
void sy_correct_px(global int2* S, int i, int j, int w, int h,
                   global const char* A, global const short* NE, global const int2* C1,
                   constant int* P, int spacing, int ew, int eh, int toroidal, int kappa) {
  // Inside a patch (the 8 neighbours continue this pixel's exemplar position, S[p + d] = S[p] + h d,
  // without wrapping a bounded exemplar) every coherent candidate is the pixel's own position:
  // keep it. Only the pixels on a join between patches are matched; at the finer levels, where
  // patches are large, that is a small share of the pixels.
  // While the spacing is at most the exemplar's smaller side, every position wrapped below lies in
  // (-n, 2n), where one step is the modulo (no division).
  const int near = spacing <= min(ew, eh);
  {
    const int2 s0 = S[(long)j * w + i];
    int inside = 1;
    if (near && i > 0 && j > 0 && i < w - 1 && j < h - 1) {
      // Away from the window's border: no clamping (the same test).
      inside = sy_inside(S + (long)j * w + i, w, s0, spacing, ew, eh, toroidal);
    } else {
      for (int dy = -1; dy <= 1 && inside; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const int ni = clamp(i + dx, 0, w - 1), nj = clamp(j + dy, 0, h - 1);
          const int2 c = S[(long)nj * w + ni];
          int ex = s0.x + (ni - i) * spacing, ey = s0.y + (nj - j) * spacing;
          if (toroidal) { ex = sy_wrap(ex, ew); ey = sy_wrap(ey, eh); }
          if (c.x != ex || c.y != ey) { inside = 0; break; }
        }
      }
    }
    if (inside) return;
  }
  const int tdx[9] = {0, -1, 1, -1, 1, 0, -1, 1, 0};
  const int tdy[9] = {0, -1, -1, 1, 1, -1, 0, 0, 1};
  // Vector arithmetic (int8 lanes): the same integer sums as channel-by-channel loops.
  int8 proj = (int8)(0);
  const int odx[9] = {0, -1, 0, 1, -1, 1, -1, 0, 1};
  const int ody[9] = {0, -1, -1, -1, 0, 0, 1, 1, 1};
#pragma unroll
  for (int t = 0; t < 9; ++t) {
    const int ni = clamp(i + tdx[t], 0, w - 1), nj = clamp(j + tdy[t], 0, h - 1);
    const int2 c = S[(long)nj * w + ni];
    const int8 v = convert_int8(vload8(0, A + 8 * ((long)c.y * ew + c.x)));
    constant int* row = P + t * 64;
    proj += v.s0 * vload8(0, row) + v.s1 * vload8(1, row) + v.s2 * vload8(2, row) + v.s3 * vload8(3, row) +
            v.s4 * vload8(4, row) + v.s5 * vload8(5, row) + v.s6 * vload8(6, row) + v.s7 * vload8(7, row);
  }
  proj >>= 8;

  int2 best = S[(long)j * w + i];  // kept if every candidate is refused
  int bestd = 0x7fffffff;
  const int margin = (!toroidal && 8 * spacing <= min(ew, eh)) ? spacing : 0;
#pragma unroll
  for (int q = 0; q < 9; ++q) {
    {
      // The pixel's own coordinate first, so it wins ties.
      const int dx = odx[q], dy = ody[q];
      const int ni = clamp(i + dx, 0, w - 1), nj = clamp(j + dy, 0, h - 1);
      const int2 c = S[(long)nj * w + ni];
#pragma unroll
      for (int kk = 0; kk < 2; ++kk) {
        int ux = c.x, uy = c.y;
        if (kk == 1) { const int2 u = C1[(long)c.y * ew + c.x]; ux = u.x; uy = u.y; }
        ux -= dx * spacing;
        uy -= dy * spacing;
        if (!toroidal) {
          // A bounded exemplar: no candidate that came across its border, and at the finer levels
          // none whose neighbourhood would leave it (patches never run across the border).
          if (ux < margin || ux >= ew - margin || uy < margin || uy >= eh - margin) continue;
        } else if (near) {
          ux = sy_step(ux, ew);
          uy = sy_step(uy, eh);
        } else {
          ux = sy_wrap(ux, ew);
          uy = sy_wrap(uy, eh);
        }
        const int8 e = proj - convert_int8(vload8(0, NE + 8 * ((long)uy * ew + ux)));
        const int8 e2 = e * e;
        const int4 e4 = e2.lo + e2.hi;
        int d = e4.x + e4.y + e4.z + e4.w;
        if (kk == 1) d += (d >> 8) * kappa;  // favour coherent candidates (patches), LH05's kappa
        if (d < bestd) { bestd = d; best = (int2)(ux, uy); }
      }
    }
  }
  S[(long)j * w + i] = best;
}
kernel void sy_correct(global int2* S, int w, int h, long ox, long oy, int parx, int pary,
                       global const char* A, global const short* NE, global const int2* C1,
                       constant int* P, int spacing, int ew, int eh, int toroidal, int kappa, int xe, int ye) {
  /*  [xe, ye): the end of the rectangle this sub-pass must cover (it starts at the launch's offset). */
  const int i = (int)((parx - (ox & 1)) & 1) + 2 * get_global_id(0);
  const int j = (int)((pary - (oy & 1)) & 1) + 2 * get_global_id(1);
  if (i >= min(w, xe) || j >= min(h, ye)) return;
  sy_correct_px(S, i, j, w, h, A, NE, C1, P, spacing, ew, eh, toroidal, kappa);
}
// Sub-passes of the refinement and the re-match: the two colours of the checkerboard of the ABSOLUTE
// coordinates (so windows agree; a tileable period is even, so the colouring is periodic too). A
// sub-pass reads the previous state (Sin) and writes every pixel to S (ping-pong buffers), so it is
// race-free although a pixel reads up to 3 px around; a pass (2 sub-passes) reaches 2x the read
// radius, which bounds the window padding. Adjacent pixels are never decided together (the cause
// of the all-at-once update's worse joins); the 3x3 / 4x4 in-place classes used before reached 9
// and 16 times the radius (18 and 48 px of padding) for 0.00-0.05 better bench coherence.
int sy_in_class(long x, long y, int parity) { return parity < 0 || (int)((x + y) & 1) == parity; }
// Seam refinement at the finest level: a pixel on a join between patches takes the coherent
// candidate of one of its 8 neighbours (u = S[p + e] - e) whose wider surroundings match best: the
// appearance vectors at the 24 taps p + d, 0 < max(|dx|, |dy|) <= 2, compared with those at u + d
// (each appearance vector already describes a 5x5 neighbourhood, so the footprint is 9x9). The
// pixel's current position competes as well and wins ties. Two sub-passes (checkerboard, above).
#ifdef SY_EXTRA  // the second program (synth::Synthesizer::Device::extra)
kernel void sy_refine(global const int2* Sin, global int2* S, int w, int h, long ox, long oy, int parity,
                      global const char* A, int ew, int eh, int toroidal) {
  const int i = get_global_id(0), j = get_global_id(1);
  if (i >= w || j >= h) return;
  const int2 s0 = Sin[(long)j * w + i];
  S[(long)j * w + i] = s0;
  if (!sy_in_class(ox + i, oy + j, parity)) return;
  int2 cand[9];
  int n = 0;
  cand[n++] = s0;
  for (int ey = -1; ey <= 1; ++ey) {
    for (int ex = -1; ex <= 1; ++ex) {
      if (ex == 0 && ey == 0) continue;
      const int ni = clamp(i + ex, 0, w - 1), nj = clamp(j + ey, 0, h - 1);
      const int2 c = Sin[(long)nj * w + ni];
      int ux = c.x - (ni - i), uy = c.y - (nj - j);
      if (toroidal) {
        ux = sy_wrap(ux, ew);
        uy = sy_wrap(uy, eh);
      } else if (ux < 2 || uy < 2 || ux >= ew - 2 || uy >= eh - 2) {
        continue;  // its surroundings would leave a bounded exemplar
      }
      int dup = 0;
      for (int k = 0; k < n; ++k) dup |= (cand[k].x == ux && cand[k].y == uy);
      if (!dup) cand[n++] = (int2)(ux, uy);
    }
  }
  if (n == 1) return;  // inside a patch: every neighbour continues it
  // The synthesised surroundings: the appearance at S[p + d].
  // Vector arithmetic (int8 lanes, summed per row): the same integer sums as per-channel loops.
  int8 ref[24];
  int t = 0;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      if (dx == 0 && dy == 0) continue;
      const int ni = clamp(i + dx, 0, w - 1), nj = clamp(j + dy, 0, h - 1);
      const int2 c = Sin[(long)nj * w + ni];
      ref[t++] = convert_int8(vload8(0, A + 8 * ((long)c.y * ew + c.x)));
    }
  }
  int2 best = s0;
  int bestd = 0x7fffffff;
  for (int c = 0; c < n; ++c) {
    int d = 0;
    t = 0;
    for (int dy = -2; dy <= 2; ++dy) {
      const int uy = toroidal ? sy_wrap(cand[c].y + dy, eh) : sy_reflect(cand[c].y + dy, eh);
      int8 acc = (int8)(0);
      for (int dx = -2; dx <= 2; ++dx) {
        if (dx == 0 && dy == 0) continue;
        const int ux = toroidal ? sy_wrap(cand[c].x + dx, ew) : sy_reflect(cand[c].x + dx, ew);
        const int8 e = ref[t++] - convert_int8(vload8(0, A + 8 * ((long)uy * ew + ux)));
        acc += e * e;
      }
      const int4 a4 = acc.lo + acc.hi;
      d += a4.x + a4.y + a4.z + a4.w;
      if (d >= bestd) break;  // cannot win any more (ties keep the earlier candidate)
    }
    if (d < bestd) { bestd = d; best = cand[c]; }
  }
  S[(long)j * w + i] = best;
}
#endif
// Final re-match at the finest level: a pixel on a join takes, among its own position (which wins
// ties), the coherent candidates of its 8 neighbours (S[p + e] - e) and the k-coherence candidates
// of the 3x3 (C1[S[p + e]] - e; with --candidates 3 also C2[S[p + e]] - e), the one whose 7x7 texels best match the texels the synthesis has
// around p (48 taps, the centre excluded; the first 8 channels, quantised). Two sub-passes
// (checkerboard, above).
// T holds the texels' first 8 channels as short8 (zero-padded): one vector load and one vector
// multiply-add per tap, summed over a row before the early-exit test (integer sums: the same result
// as the channel-by-channel loop).
// Appends candidate u (wrapped on a torus; on a bounded exemplar refused when its 7x7 would leave
// it) unless it is already in the list; returns the new count. The order of the calls is the
// order of the list, and the first of equally good candidates wins.
int sy_candidate(int2* cand, int n, int2 u, int ew, int eh, int toroidal) {
  if (toroidal) {
    u.x = sy_step(u.x, ew);
    u.y = sy_step(u.y, eh);
  } else if (u.x < 3 || u.y < 3 || u.x >= ew - 3 || u.y >= eh - 3) {
    return n;
  }
  const long l = as_long(u);
  int dup = 0;
  for (int k = 0; k < n; ++k) dup |= as_long(cand[k]) == l;
  if (!dup) cand[n++] = u;
  return n;
}
#define SY_REMATCH(NAME, VT, IT, CONVERT, HSUM, ROWDIST) \
kernel void NAME(global const int2* Sin, global int2* S, int w, int h, long ox, long oy, int parity, \
                       global const VT* T, global const int2* C1, global const int2* C2, int kc, int ew, int eh, int toroidal, int kmode, \
                       int xe, int ye) { \
  /*  One work-item per pixel of this sub-pass's colour (S already holds a copy of Sin). The window's */ \
  /*  outermost ring is never re-matched (its 3x3 would be clamped): it lies in the padding, which the */ \
  /*  re-match's reach (3 px per sub-pass) never carries into the window. */ \
  const int j = get_global_id(1); \
  if (j >= h) return; \
  const int i = (int)((parity - ((ox + oy + j) & 1)) & 1) + 2 * (int)get_global_id(0); \
  /*  [xe, ye): the end of the rectangle this sub-pass must cover (it starts at the launch's offset). */ \
  if (i >= min(w - 1, xe) || i == 0 || j == 0 || j >= min(h - 1, ye)) return; \
  const long p = (long)j * w + i; \
  const int2 s0 = Sin[p]; \
  /*  The 3x3 around p (no clamping: p is not on the ring), row by row. */ \
  global const int2* q = Sin + p; \
  { \
    /*  Inside a patch (every neighbour d continues it: S[p + d] - d = S[p], toroidal: modulo) the 7x7 */ \
    /*  matches exactly: keep. */ \
    if (sy_inside(q, w, s0, 1, ew, eh, toroidal)) return; \
  } \
  const int2 nb[9] = {q[-w - 1], q[-w], q[-w + 1], q[-1], s0, q[1], q[w - 1], q[w], q[w + 1]}; \
  int2 cand[27]; \
  int n = 0; \
  cand[n++] = s0; \
  for (int e = 0; e < 9; ++e) { \
    const int2 d = (int2)(e % 3 - 1, e / 3 - 1); \
    const int2 c = nb[e]; \
    if (e != 4) n = sy_candidate(cand, n, c - d, ew, eh, toroidal); \
    if (kmode == 2 || (kmode == 1 && e == 4)) { \
      n = sy_candidate(cand, n, C1[(long)c.y * ew + c.x] - d, ew, eh, toroidal); \
      if (kc >= 2) n = sy_candidate(cand, n, C2[(long)c.y * ew + c.x] - d, ew, eh, toroidal); \
    } \
  } \
  if (n == 1) return; \
  /*  The texels the synthesis has around p, row by row (7 per row, the centre zero and never used). */ \
  IT ref[49]; \
  if (i >= 3 && j >= 3 && i < w - 3 && j < h - 3) { \
    for (int dy = -3; dy <= 3; ++dy) { \
      global const int2* row = Sin + (long)(j + dy) * w + i - 3; \
      _Pragma("unroll") \
      for (int dx = 0; dx < 7; ++dx) ref[(dy + 3) * 7 + dx] = CONVERT(T[(long)row[dx].y * ew + row[dx].x]); \
    } \
  } else { \
    for (int dy = -3; dy <= 3; ++dy) { \
      const int nj = clamp(j + dy, 0, h - 1); \
      for (int dx = -3; dx <= 3; ++dx) { \
        const int2 q = Sin[(long)nj * w + clamp(i + dx, 0, w - 1)]; \
        ref[(dy + 3) * 7 + dx + 3] = CONVERT(T[(long)q.y * ew + q.x]); \
      } \
    } \
  } \
  int2 best = s0; \
  int bestd = 0x7fffffff; \
  for (int k = 0; k < n; ++k) { \
    const int cx = cand[k].x, cy = cand[k].y; \
    /*  Away from a bounded exemplar's border (every candidate but possibly s0) no mirroring is needed. */ \
    const int plain = toroidal || (cx >= 3 && cy >= 3 && cx < ew - 3 && cy < eh - 3); \
    const int inner_x = cx >= 3 && cx < ew - 3; \
    /*  Squared differences summed in vector lanes; after rows 1, 3, 5 and 7 the lanes are */ \
    /*  added up and a candidate that can no longer win is left (the sums only grow, so where it is */ \
    /*  left does not change which candidate wins). */ \
    int d = 0; \
    IT acc = (IT)(0); \
    for (int dy = -3; dy <= 3; ++dy) { \
      const int uy = plain ? sy_step(cy + dy, eh) : sy_reflect(cy + dy, eh); \
      global const VT* row = T + (long)uy * ew; \
      const IT* rr = ref + (dy + 3) * 7; \
      if (inner_x) { \
        /*  The common case: the row does not wrap, one contiguous run of 7 texels. */ \
        acc += ROWDIST(rr, row + cx - 3, dy == 0); \
      } else { \
        for (int dx = -3; dx <= 3; ++dx) { \
          if (dx == 0 && dy == 0) continue; \
          const int ux = plain ? sy_step(cx + dx, ew) : sy_reflect(cx + dx, ew); \
          const IT e = rr[dx + 3] - CONVERT(row[ux]); \
          acc += e * e; \
        } \
      } \
      if (dy & 1) { \
        d += HSUM(acc); \
        acc = (IT)(0); \
        if (d >= bestd) break; \
      } \
    } \
    if (d < bestd) { bestd = d; best = cand[k]; } \
  } \
  S[(long)j * w + i] = best; \
}
int sy_hsum8(int8 a) { const int4 a4 = a.lo + a.hi; const int2 a2 = a4.lo + a4.hi; return a2.x + a2.y; }
int sy_hsum4(int4 a) { const int2 a2 = a.lo + a.hi; return a2.x + a2.y; }
// The squared distance of a row of 7 texels (the centre one skipped when `centre`): per tap, as the
// wrapping path does, for 8 channels.
int8 sy_row8(const int8* rr, global const short8* t, int centre) {
  int8 acc = (int8)(0);
  for (int dx = 0; dx < 7; ++dx) {
    if (centre && dx == 3) continue;
    const int8 e = rr[dx] - convert_int8(t[dx]);
    acc += e * e;
  }
  return acc;
}
// ... for colour alone (short4 texels): the 7 texels are 28 contiguous shorts, loaded as 16 + 8 + 4
// and compared in wide vectors (the same integer sum; the centre's lanes zeroed).
int4 sy_row4(const int4* rr, global const short4* t, int centre) {
  global const short* ts = (global const short*)t;
  const int16 a = (int16)(rr[0], rr[1], rr[2], rr[3]);
  const int8 b = (int8)(rr[4], rr[5]);
  int16 ea = a - convert_int16(vload16(0, ts));
  if (centre) ea.hi.hi = (int4)(0);
  const int8 eb = b - convert_int8(vload8(0, ts + 16));
  const int4 ec = rr[6] - convert_int4(vload4(0, ts + 24));
  const int16 sa = ea * ea;
  const int8 s8 = sa.lo + sa.hi + eb * eb;
  return s8.lo + s8.hi + ec * ec;
}
// Up to 8 channels as short8; colour alone (3 channels) as short4: half the loads and lanes, the
// same sums (the padding lanes are zero).
#ifdef SY_EXTRA
SY_REMATCH(sy_rematch, short8, int8, convert_int8, sy_hsum8, sy_row8)
#endif
SY_REMATCH(sy_rematch4, short4, int4, convert_int4, sy_hsum4, sy_row4)
)CL";

struct Region {
  int64_t x = 0, y = 0;
  int w = 0, h = 0;
};

int ctz64(int64_t v) {
  int n = 0;
  while (v > 0 && (v & 1) == 0) v >>= 1, ++n;
  return n;
}

using detail::kMaxCoordinate;

// Which k-coherence candidates the re-match tries: 0 none, 1 the pixel's own, 2 those of the 3x3.
constexpr int kRematchCoherence = 2;

template <typename... Args>
void launch2d(cl::Kernel& kernel, int gx, int gy, const Args&... args) {
  detail::launch2d("launching a synthesis kernel", kernel, gx, gy, args...);
}

// Enqueues `kernel` (arguments set) over gx x gy work-items from (gx0, gy0), the range rounded up
// to whole work-groups: the kernels test their own end (xe, ye).
void enqueue_from(cl::Kernel& kernel, int gx0, int gy0, int gx, int gy) {
  using detail::kLocalX, detail::kLocalY;
  const int rx = (gx + kLocalX - 1) / kLocalX * kLocalX, ry = (gy + kLocalY - 1) / kLocalY * kLocalY;
  ocl::Runtime::instance().queue().enqueueNDRangeKernel(kernel, cl::NDRange(gx0, gy0), cl::NDRange(rx, ry),
                                                        cl::NDRange(kLocalX, kLocalY));
}

}  // namespace

struct Synthesizer::DeviceLevel {
  cl::Buffer appearance, neighbourhood, coherent, coherent2, projection;
  bool has_candidates = false, has_matching = false;
};

struct Synthesizer::Device {
  // The kernels every synthesis uses; the seam refinement and the re-match of colour + maps
  // (short8) are in a second program built with SY_EXTRA, loaded only when needed (PoCL's binary
  // load time grows with the code in a program: ~1 ms less for the default command).
  cl::Program program, extra;
  cl::Kernel upsample, correct, refine, rematch, rematch4;
  cl::Buffer texels;
  int texel_channels = 0;
  std::vector<DeviceLevel> levels;
};

void check_options(const Analysis& a, const SynthOptions& o) {
  if (o.randomness.empty()) throw UsageError("--randomness needs at least one value");
  if (static_cast<int>(o.randomness.size()) > a.levels) {
    throw UsageError(fmt::format("--randomness has {} values but this exemplar has {} levels", o.randomness.size(),
                                 a.levels),
                     "give one value, or at most one per level, coarse to fine");
  }
  for (float r : o.randomness) {
    if (!(r >= 0.0f && r <= 4.0f)) {
      throw UsageError(fmt::format("randomness {} is outside [0, 4]", r), "0 = tiling, 1 = up to one level spacing (default 1,0: jitter the first level only)");
    }
  }
  if (!o.jitter_map.empty() &&
      (o.jitter_map_width <= 0 || o.jitter_map_height <= 0 ||
       o.jitter_map.size() != static_cast<size_t>(o.jitter_map_width) * o.jitter_map_height))
    throw UsageError("the jitter map's size does not match its pixels");
  for (const auto& p : o.pastes) {
    if (p.width <= 0 || p.height <= 0 || p.ex_x < 0 || p.ex_y < 0 || p.ex_x + p.width > a.width ||
        p.ex_y + p.height > a.height)
      throw UsageError(fmt::format("paste rectangle {},{},{},{} is not inside the {}x{} exemplar", p.ex_x, p.ex_y,
                                   p.width, p.height, a.width, a.height));
    if (std::llabs(p.out_x) > kMaxCoordinate || std::llabs(p.out_y) > kMaxCoordinate)
      throw UsageError("the paste position is too large", "positions must lie within +-2^60");
  }
  if (o.passes.empty()) throw UsageError("--passes needs at least one value");
  if (static_cast<int>(o.passes.size()) > a.levels) {
    throw UsageError(fmt::format("--passes has {} values but this exemplar has {} levels", o.passes.size(), a.levels),
                     "give one value, or at most one per level, coarse to fine");
  }
  for (int p : o.passes)
    if (p < 0 || p > 8) throw UsageError("--passes must be in [0, 8]");
  if (o.finest_passes < -1 || o.finest_passes > 8) throw UsageError("--finest-passes must be in [0, 8]");
  if (o.refine_passes < 0 || o.refine_passes > 8) throw UsageError("--refine-seams must be in [0, 8]");
  if (o.rematch_passes < 0 || o.rematch_passes > 8) throw UsageError("--rematch must be in [0, 8]");
  if (o.rematch_candidate_passes < 0 || o.rematch_candidate_passes > 8)
    throw UsageError("--rematch-candidates must be in [0, 8]");
  if (!(o.layout_min_correlation >= -1 && o.layout_min_correlation <= 1))
    throw UsageError(fmt::format("--layout-min-correlation must be in [-1, 1], got {}", o.layout_min_correlation));
  if (!(o.break_pieces >= 0 && o.break_pieces <= 1))
    throw UsageError(fmt::format("--break-pieces must be in [0, 1], got {}", o.break_pieces));
  if (o.layout_shifts < 0 || o.layout_shifts > kMaxShifts)
    throw UsageError(fmt::format("--layout-shifts must be in [0, {}]", kMaxShifts), "0 = uniform random shifts");
  if (o.period_x < 0 || o.period_y < 0 || o.period_x > (1 << 24) || o.period_y > (1 << 24))
    throw UsageError("the tiling period must be in [2, 16777216]");
  if ((o.period_x > 0) != (o.period_y > 0)) throw UsageError("give a period along both axes or neither");
  if (o.period_x > 0 && (o.period_x % 2 != 0 || o.period_y % 2 != 0)) {
    throw UsageError(fmt::format("a tileable output needs an even size, got {}x{}", o.period_x, o.period_y),
                     "use a size that is a multiple of a large power of two (e.g. 512 or 1024)");
  }
}

int first_level(const Analysis& a, const SynthOptions& o) {
  if (o.period_x <= 0) return 1;
  const int tz = std::min(ctz64(o.period_x), ctz64(o.period_y));
  return std::max(1, a.levels - tz + 1);
}

int layout_shift_count(const Analysis& a, const SynthOptions& o) {
  const int n = std::min<int>(o.layout_shifts, static_cast<int>(std::min(a.shifts.size() / 2, a.shift_correlation.size())));
  if (n <= 0) return 0;
  double mean = 0;
  for (int k = 0; k < n; ++k) mean += a.shift_correlation[static_cast<size_t>(k)];
  return mean / n >= o.layout_min_correlation ? n : 0;
}

int passes_at(const Analysis& a, const SynthOptions& o, int level) {
  if (level == a.levels && o.finest_passes >= 0) return o.finest_passes;
  if (o.passes.empty()) return 0;
  const int i = std::clamp(level - first_level(a, o), 0, static_cast<int>(o.passes.size()) - 1);
  return o.passes[static_cast<size_t>(i)];
}

void warm_up() {
  auto& rt = ocl::Runtime::instance();
  if (!timing::enabled()) rt.program(kSource, "-cl-std=CL1.2");
}

Synthesizer::Synthesizer(const Analysis& analysis) : analysis_(analysis), device_(std::make_unique<Device>()) {
  auto& rt = ocl::Runtime::instance();
  timing::mark("OpenCL platform, context, queue");
  device_->program = rt.program(kSource, "-cl-std=CL1.2");
  ocl::with_cl_errors("creating the synthesis kernels", [&] {
    device_->upsample = cl::Kernel(device_->program, "sy_upsample");
    device_->correct = cl::Kernel(device_->program, "sy_correct");
    device_->rematch4 = cl::Kernel(device_->program, "sy_rematch4");
    return 0;
  });
  timing::mark("program build / binary cache load");
  if (!analysis.texels.empty()) {
    // The re-match compares the first 8 channels: one zero-padded short8 per texel, or short4 when
    // there are at most 4 (colour alone).
    const int C = analysis.texel_channels;
    const int lanes = C <= 4 ? 4 : 8;
    const size_t n = analysis.texels.size() / static_cast<size_t>(C);
    std::vector<int16_t> t8(n * lanes, 0);
    for (size_t i = 0; i < n; ++i)
      for (int c = 0; c < std::min(C, lanes); ++c) t8[i * lanes + c] = analysis.texels[i * C + c];
    device_->texels = ocl::upload(t8);
    device_->texel_channels = C;
  }
  // Levels are uploaded when a synthesis first needs them (level(l)): with the defaults the first
  // two levels and level 0 are never corrected, and the finest level needs only its candidates.
  device_->levels.resize(analysis.level.size());
  timing::mark("analysis upload to the device");
}

Synthesizer::~Synthesizer() = default;

// Level l's buffers on the device: the correction's (appearance, neighbourhoods, candidates,
// projection) or only the candidates (the re-match's), uploaded on first use.
const Synthesizer::DeviceLevel& Synthesizer::level(int l, bool correction) {
  auto& d = device_->levels[static_cast<size_t>(l)];
  const AnalysisLevel& lv = analysis_.level[static_cast<size_t>(l)];
  if (!d.has_candidates) {
    // The k-coherence candidates as (x, y) pairs: no division per candidate in the kernels.
    auto pairs = [&](const std::vector<int32_t>& idx) {
      std::vector<cl_int2> xy(idx.size());
      for (size_t i = 0; i < idx.size(); ++i) xy[i] = cl_int2{{idx[i] % analysis_.width, idx[i] / analysis_.width}};
      return ocl::upload(xy);
    };
    d.coherent = pairs(lv.coherent);
    // k = 2: the re-match never reads the third candidate (kc = 1); the buffer is a stand-in.
    d.coherent2 = lv.coherent2.empty() ? d.coherent : pairs(lv.coherent2);
    d.has_candidates = true;
  }
  if (correction && !d.has_matching) {
    d.appearance = ocl::upload(lv.appearance);
    d.neighbourhood = ocl::upload(lv.neighbourhood);
    d.projection = ocl::upload(lv.projection);
    d.has_matching = true;
  }
  return d;
}

std::vector<int32_t> Synthesizer::synthesise(const Window& win, const SynthOptions& o) {
  const Analysis& a = analysis_;
  check_options(a, o);
  if (win.width <= 0 || win.height <= 0) throw UsageError("the window must have a positive width and height");
  if (std::llabs(win.x) > kMaxCoordinate || std::llabs(win.y) > kMaxCoordinate) {
    throw UsageError("the window offset is too large", "offsets must lie within +-2^60");
  }
  const int L = a.levels;
  const int l0 = first_level(a, o);
  // The reach of level l's correction: each sub-pass reads one pixel around, 4 per pass.
  // At the finest level the seam refinement's 2 sub-passes read 2 pixels around each, the re-match's
  // 2 sub-passes 3 pixels.
  const int rematch = a.texels.empty() ? 0 : o.rematch_passes;
  auto pad_at = [&](int l) { return 4 * passes_at(a, o, l) + 2 + (l == L ? 4 * o.refine_passes + 6 * rematch : 0); };
  const int pad = pad_at(L);
  // Regions, finest first: E_L = window + pad_L; E_{l-1} = parents(E_l) + pad_{l-1}.
  std::vector<Region> region(L + 1);
  region[L] = {win.x - pad, win.y - pad, win.width + 2 * pad, win.height + 2 * pad};
  for (int l = L; l > l0; --l) {
    const int pp = pad_at(l - 1);
    const Region& r = region[l];
    const int64_t px0 = r.x >> 1, py0 = r.y >> 1;
    const int64_t px1 = (r.x + r.w - 1) >> 1, py1 = (r.y + r.h - 1) >> 1;
    region[l - 1] = {px0 - pp, py0 - pp, static_cast<int>(px1 - px0 + 1) + 2 * pp,
                     static_cast<int>(py1 - py0 + 1) + 2 * pp};
  }

  auto& dev = *device_;
  // Spatially varying randomness: 0..255 per pixel of a map that tiles the plane (255 = r_l).
  const bool has_map = !o.jitter_map.empty();
  const int jw = has_map ? o.jitter_map_width : 0, jh = has_map ? o.jitter_map_height : 1;
  const std::vector<uint8_t> full{255};
  cl::Buffer jmap = ocl::upload(has_map ? o.jitter_map : full);
  cl::Buffer parent = ocl::output_buffer(sizeof(cl_int2));
  Region parent_region;
  bool parent_zero = true;
  for (int l = l0; l <= L; ++l) {
    const Region& r = region[l];
    const int spacing = 1 << (L - l);
    const size_t count = static_cast<size_t>(r.w) * r.h;
    cl::Buffer S = ocl::with_cl_errors("allocating synthesis level", [&] {
      return cl::Buffer(ocl::Runtime::instance().context(), CL_MEM_READ_WRITE, count * sizeof(cl_int2));
    });
    // The list starts at the first synthesised level (level 1, or the coarsest level a tileable
    // period allows), so the layout-changing first value is never skipped.
    const size_t ri = static_cast<size_t>(std::min<int>(l - l0, static_cast<int>(o.randomness.size()) - 1));
    const float rl = o.randomness[ri];
    cl_int rq = static_cast<cl_int>(std::lround(rl * 65536.0));
    const cl_long period_x = o.period_x > 0 ? o.period_x >> (L - l) : 0;
    const cl_long period_y = o.period_y > 0 ? o.period_y >> (L - l) : 0;
    // A paste's coordinates at level l: S_l[q] = h_l q + (ex - out) + (c_l - c_L), where c is the
    // constant the upsampling offsets accumulate (c_{k+1} = c_k - ceil(h_{k+1} / 2)), so that the
    // finest level copies the rectangle exactly.
    int64_t c_gap = 0;
    for (int k = l + 1; k <= L; ++k) c_gap += ((int64_t(1) << (L - k)) + 1) / 2;
    std::vector<cl_long> paste_data;
    for (const auto& p : o.pastes) {
      paste_data.insert(paste_data.end(), {p.out_x, p.out_y, p.width, p.height, p.ex_x - p.out_x + c_gap,
                                           p.ex_y - p.out_y + c_gap});
    }
    cl::Buffer paste_buffer = ocl::upload(paste_data);
    // Structure-keeping shifts at the first synthesised level only.
    // ... and, with probability break_pieces, at the second (replacing its randomness value).
    const int usable_shifts = layout_shift_count(a, o);
    const bool breaking = l == l0 + 1 && o.break_pieces > 0 && usable_shifts > 0;
    const int shift_count = l == l0 || breaking ? usable_shifts : 0;
    const cl_int shift_prob = breaking ? static_cast<cl_int>(std::lround(o.break_pieces * 65536.0)) : 65536;
    if (breaking) rq = 65536;
    std::vector<cl_int> shift_data(static_cast<size_t>(std::max(2, 2 * shift_count)), 0);  // never empty
    std::copy_n(a.shifts.begin(), 2 * shift_count, shift_data.begin());
    cl::Buffer shift_buffer = ocl::upload(shift_data);
    launch2d(dev.upsample, r.w, r.h, parent, static_cast<cl_int>(parent_region.w),
                static_cast<cl_long>(parent_region.x), static_cast<cl_long>(parent_region.y),
                static_cast<cl_int>(parent_zero ? 1 : 0), S, static_cast<cl_int>(r.w), static_cast<cl_int>(r.h),
                static_cast<cl_long>(r.x), static_cast<cl_long>(r.y), static_cast<cl_int>(spacing),
                static_cast<cl_int>(a.width), static_cast<cl_int>(a.height), period_x, period_y, rq,
                static_cast<cl_uint>(o.seed), static_cast<cl_uint>(l), jmap, static_cast<cl_int>(jw),
                static_cast<cl_int>(jh), static_cast<cl_int>(L - l), paste_buffer,
                static_cast<cl_int>(o.pastes.size()), shift_buffer, static_cast<cl_int>(shift_count), shift_prob);
    auto phase = [&](const char* what) {
      if (!timing::enabled()) return;
      ocl::finish();
      timing::mark(fmt::format("level {} {} ({}x{})", l, what, r.w, r.h));
    };
    phase("upsample + jitter");
    const int level_passes = passes_at(a, o, l);
    const auto& lv = level(l, level_passes > 0 || (l == L && o.refine_passes > 0));
    for (int pass = 0; pass < level_passes; ++pass) {
      for (int sub = 0; sub < 4; ++sub) {
        const int parx = sub & 1, pary = sub >> 1;
        // Only the pixels the level still depends on: after its K = 4 passes sub-passes the level is
        // needed inset by K + 2 (the parents of the finer level's region, or at the finest level the
        // window and the re-match's reach); a sub-pass reads 1 px around, so sub-pass k needs the
        // rectangle inset by 3 + k (no pixel in it reads a clamped neighbour; the bytes do not change).
        const int m = std::min(3 + 4 * pass + sub, 4 * level_passes + 2);
        const int xe = r.w - m, ye = r.h - m;
        const int gx0 = std::max(m / 2 - 1, 0), gy0 = std::max(m / 2 - 1, 0);
        const int gx = std::max((xe + 1) / 2 + 1 - gx0, 1), gy = std::max((ye + 1) / 2 + 1 - gy0, 1);
        ocl::with_cl_errors("launching a synthesis kernel", [&] {
          cl_uint index = 0;
          cl::Kernel& k = dev.correct;
          k.setArg(index++, S), k.setArg(index++, static_cast<cl_int>(r.w)), k.setArg(index++, static_cast<cl_int>(r.h));
          k.setArg(index++, static_cast<cl_long>(r.x)), k.setArg(index++, static_cast<cl_long>(r.y));
          k.setArg(index++, static_cast<cl_int>(parx)), k.setArg(index++, static_cast<cl_int>(pary));
          k.setArg(index++, lv.appearance), k.setArg(index++, lv.neighbourhood), k.setArg(index++, lv.coherent);
          k.setArg(index++, lv.projection), k.setArg(index++, static_cast<cl_int>(spacing));
          k.setArg(index++, static_cast<cl_int>(a.width)), k.setArg(index++, static_cast<cl_int>(a.height));
          k.setArg(index++, static_cast<cl_int>(a.toroidal ? 1 : 0));
          k.setArg(index++, static_cast<cl_int>(std::lround(o.kappa * 256)));
          k.setArg(index++, static_cast<cl_int>(xe)), k.setArg(index++, static_cast<cl_int>(ye));
          enqueue_from(k, gx0, gy0, gx, gy);
          return 0;
        });
      }
    }
    if (passes_at(a, o, l) > 0) phase("correction");
    if (l == L && (o.refine_passes > 0 || rematch > 0)) {
      // Ping-pong between S and a second buffer: each sub-pass reads the previous state.
      cl::Buffer other = ocl::with_cl_errors("allocating synthesis level", [&] {
        return cl::Buffer(ocl::Runtime::instance().context(), CL_MEM_READ_WRITE, count * sizeof(cl_int2));
      });
      auto run = [&](cl::Kernel& kernel, int passes, auto&&... rest) {
        for (int sub = 0; sub < 2 * passes; ++sub) {
          launch2d(kernel, r.w, r.h, S, other, static_cast<cl_int>(r.w), static_cast<cl_int>(r.h),
                   static_cast<cl_long>(r.x), static_cast<cl_long>(r.y), static_cast<cl_int>(sub & 1), rest...);
          std::swap(S, other);
        }
      };
      const bool eight = dev.texel_channels > 4;
      if ((o.refine_passes > 0 || (rematch > 0 && eight)) && !dev.extra()) {
        dev.extra = ocl::Runtime::instance().program(kSource, "-cl-std=CL1.2 -DSY_EXTRA");
        ocl::with_cl_errors("creating the synthesis kernels", [&] {
          dev.refine = cl::Kernel(dev.extra, "sy_refine");
          dev.rematch = cl::Kernel(dev.extra, "sy_rematch");
          return 0;
        });
      }
      run(dev.refine, o.refine_passes, lv.appearance, static_cast<cl_int>(a.width), static_cast<cl_int>(a.height),
          static_cast<cl_int>(a.toroidal ? 1 : 0));
      if (o.refine_passes > 0) phase("seam refinement");
      // k = 3 (--candidates 3): the third candidate only here, where the 7x7 texels decide. In the
      // correction it made the bench worse (median coherence 5.05 -> 5.24; docs/synth.md, seventh pass).
      // Each sub-pass: S is copied to the other buffer, then the matching kernel runs over this
      // sub-pass's colour of the checkerboard (half the pixels) and writes the ones it changes.
      if (rematch > 0) {
        cl::Kernel& match = eight ? dev.rematch : dev.rematch4;
        for (int sub = 0; sub < 2 * rematch; ++sub) {
          ocl::with_cl_errors("copying a synthesis level", [&] {
            return ocl::Runtime::instance().queue().enqueueCopyBuffer(S, other, 0, 0, count * sizeof(cl_int2));
          });
          // Only the pixels the window still depends on: each later sub-pass reads 3 px around, so
          // sub-pass `sub` covers the window widened by 3 px per sub-pass left (the rest of the
          // padding keeps its copied values; the window's bytes do not change).
          const int m = pad - 3 * (2 * rematch - 1 - sub);
          const int x0 = std::max(m, 1), y0 = std::max(m, 1);
          const int xe = r.w - m, ye = r.h - m;
          const int gx0 = std::max(x0 / 2 - 1, 0), gx = (xe + 1) / 2 + 1 - gx0, gy = ye - y0;
          ocl::with_cl_errors("launching a synthesis kernel", [&] {
            cl_uint index = 0;
            match.setArg(index++, S), match.setArg(index++, other), match.setArg(index++, static_cast<cl_int>(r.w));
            match.setArg(index++, static_cast<cl_int>(r.h)), match.setArg(index++, static_cast<cl_long>(r.x));
            match.setArg(index++, static_cast<cl_long>(r.y)), match.setArg(index++, static_cast<cl_int>(sub & 1));
            match.setArg(index++, dev.texels), match.setArg(index++, lv.coherent), match.setArg(index++, lv.coherent2);
            match.setArg(index++, static_cast<cl_int>(a.candidates - 1)), match.setArg(index++, static_cast<cl_int>(a.width));
            match.setArg(index++, static_cast<cl_int>(a.height)), match.setArg(index++, static_cast<cl_int>(a.toroidal ? 1 : 0));
            match.setArg(index++, static_cast<cl_int>(sub / 2 < o.rematch_candidate_passes ? kRematchCoherence : 0));
            match.setArg(index++, static_cast<cl_int>(xe)), match.setArg(index++, static_cast<cl_int>(ye));
            enqueue_from(match, gx0, y0, gx, gy);
            return 0;
          });
          std::swap(S, other);
        }
      }
    }
    if (l == L && rematch > 0) phase("re-match");
    parent = S;
    parent_region = r;
    parent_zero = false;
  }
  // Read back the window's rows.
  std::vector<int32_t> out(static_cast<size_t>(win.width) * win.height * 2);
  const Region& r = region[L];
  // One rectangular read of the window (a read per row cost ~8 us each; reading the padded rows
  // and cutting the columns on the host touched 2 MB more for a 512^2 window).
  ocl::with_cl_errors("reading a device buffer", [&] {
    const cl::array<cl::size_type, 3> origin{sizeof(cl_int2) * pad, static_cast<cl::size_type>(pad), 0};
    const cl::array<cl::size_type, 3> host{0, 0, 0};
    const cl::array<cl::size_type, 3> size{sizeof(cl_int2) * win.width, static_cast<cl::size_type>(win.height), 1};
    return ocl::Runtime::instance().queue().enqueueReadBufferRect(parent, CL_TRUE, origin, host, size,
                                                                  sizeof(cl_int2) * r.w, 0, sizeof(cl_int2) * win.width,
                                                                  0, out.data());
  });
  timing::mark("readback");
  return out;
}

}  // namespace proctex::synth
