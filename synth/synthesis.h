#pragma once
// Parallel controllable synthesis (Lefebvre & Hoppe 2005) on OpenCL: per level, upsample the
// exemplar coordinates, jitter them with a hash of the ABSOLUTE pixel position (and level, seed),
// then correct them in passes of 4 sub-passes (2x2 parity classes) using the analysis's
// appearance-space neighbourhoods and k-coherence candidates. All matching is integer arithmetic,
// so results are bit-identical for any thread count and any device.
//
// Spatial determinism: the plane is infinite; synthesise(window) computes only the window plus
// the dependency cone of every coarser level (padding), and equals the same region of any larger
// synthesis with the same options.
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "synth/analysis.h"

namespace proctex::synth {

struct Window {
  int64_t x = 0, y = 0;  // top-left pixel on the infinite plane (negative and huge offsets work)
  int width = 0, height = 0;
};

// The defaults of a synthesis from one exemplar, by `proctex synth` and by the service's synth jobs
// alike (the same request gives the same pixels): a stronger coherence with a 4 px seam blend
// (issue 13, fifth pass: bench median coherence 5.14 -> 5.04, docs/synth.md). SynthOptions{} and
// RenderOutputs{} keep the library's 8 and 3 for rgbn and for graphs.
inline constexpr float kSingleExemplarCoherence = 32.0f;
inline constexpr int kSingleExemplarBlendRadius = 4;

struct SynthOptions {
  uint32_t seed = 1;
  // Jitter strength r_l per synthesised level, coarse to fine (from first_level() to L: levels 1..L
  // unless a tileable period skips the coarsest); one value applies to
  // every level, a shorter list repeats its last value for the finer levels. 0 = a plain tiling.
  // r_l = 1 jitters by up to +-h_l. Default: jitter only the first level, where +-h_1 (h_1 >= half
  // the exemplar) reaches any source position: patches of about half the exemplar, re-joined by
  // the correction at every finer level; see docs/synth.md for the measures behind it.
  std::vector<float> randomness = {1.0f, 0.0f};
  // Correction passes (each 4 sub-passes) per synthesised level, coarse to fine like randomness
  // (one value applies to every level; a shorter list repeats its last value). Default: none at
  // the first level (there the correction pulled the jittered blocks back to the plain tiling, a
  // visible lattice), none at the second either (issue 13, session 10: its correction merged the
  // first level's blocks into copies of up to 3.5 exemplars - brick, marble and wood looked like the
  // exemplar shifted; bench median coherence 5.04 -> 5.05, largest piece 0.47 -> 0.34), 2 below.
  std::vector<int> passes = {0, 0, 2};
  // Passes at the finest level (the most pixels), overriding `passes` there; -1 = as `passes`.
  // 1 (issue 13, fourth pass): with two re-match passes after it, a second correction pass changed
  // no bench measure by more than 0.02 and cost ~12 ms CPU of a 512^2 run (docs/synth.md).
  // 0 since session 12: the re-match that follows joins the patches on the bench's own 7x7
  // footprint; without the correction before it the bench median coherence stays at 5.06 (5.06
  // with it, 5.05 with both re-match passes on k-coherence candidates), for ~12 ms less CPU and
  // 4 px less padding per 512^2 command.
  int finest_passes = 0;
  // Seam refinement passes at the finest level (each 2 checkerboard sub-passes): pixels on a join
  // take the neighbour's patch whose 9x9 surroundings (appearance vectors) match best, moving joins
  // to where the patches agree. 0 by default since the fourth pass: two re-match passes without it
  // give the bench coherence of the old defaults (refinement + one re-match in 3x3 / 4x4 classes);
  // with it they are 0.00-0.03 better at +18 ms CPU per 512^2 (docs/synth.md).
  int refine_passes = 0;
  // Final re-match passes at the finest level (each 2 checkerboard sub-passes), after the seam
  // refinement: a pixel on a join takes, among its own position, the coherent candidates of its 8
  // neighbours (S[p + e] - e) and their k-coherence candidates, the one whose 7x7 texels (the
  // bench's patch footprint, colour and maps, not appearance vectors) match the synthesised 7x7
  // surroundings best. 2: brick/grass/pave/rock coherence 4.01 / 5.14 / 6.82 / 5.53 against
  // 4.00 / 5.15 / 6.82 / 5.52 for the old defaults; one pass: 4.03 / 5.15 / 6.86 / 5.57.
  int rematch_passes = 2;
  // How many re-match passes, from the first, also try the k-coherence candidates; the later ones try
  // only the neighbours' patches (and the pixel's own position). 1 since session 12: the second pass
  // with them cost ~15 ms CPU of a 512^2 run for 0.00-0.04 better bench coherence (median 5.05
  // against 5.06; docs/synth.md, eighth pass).
  int rematch_candidate_passes = 1;
  // Layout jitter restricted to structure-keeping shifts: at the first synthesised level a pixel
  // (a block of h_l x h_l output pixels) is shifted by one of the exemplar's `layout_shifts` most
  // self-similar translations (Analysis::shifts; drawn by the same position hash) instead of by a
  // uniform random shift of up to +-r h_l, so adjacent blocks differ by a shift that keeps the
  // structure (brick rows stay aligned). 0 = uniform shifts. The randomness value of that level
  // only switches it on (r > 0) or off (r = 0); a jitter map turns it off where it is 0. 32: brick's
  // coherence 5.5 -> 4.0 and median completeness 6.8 -> 2.3 on the bench (8: more verbatim copying).
  int layout_shifts = 32;
  // Breaking up large copied pieces (issue 13): at the second synthesised level (blocks of h_l / 2
  // output pixels) a pixel takes a further layout shift (one of the same `layout_shifts`
  // translations, its own hash draw) with this probability, so that two adjacent first-level
  // blocks that happen to continue each other are cut into smaller pieces. 0 = off. Needs
  // layout_shifts > 0; a jitter map turns it off where it is 0.
  float break_pieces = 0.0f;
  // The layout shifts are used only when the mean correlation of the exemplar with itself under
  // its first `layout_shifts` shifts (Analysis::shift_correlation) is at least this; otherwise
  // the first level is jittered by uniform random shifts (as with layout_shifts = 0). 0: only an
  // exemplar whose "peaks" are anti-correlated loses them - of the bench's exemplars only dirt
  // (-0.19: its peaks all sat near half the exemplar and laid its one orange region out on a
  // 128 px lattice); brick 0.43, pave 0.27, planks 0.26, the others 0.06-0.12. 0.2 (shifts for
  // brick, pave and planks only) broke up the large pieces of the others but worsened 6 of their
  // 7 coherences (grass 5.14 -> 5.31, marble 10.88 -> 11.48) and the completeness median.
  float layout_min_correlation = 0.0f;
  // Coherence bias (LH05's kappa): a k-coherence candidate must beat a coherent one (that grows
  // a patch) by this factor: distance * (1 + kappa). 0 = plain nearest neighbourhood.
  float kappa = 8.0f;
  // Spatially varying randomness (Lefebvre's jitter map): 0..255 per pixel, scaling r_l at the
  // finest-level pixel; the map repeats over the plane from (0, 0). Empty = 255 everywhere.
  std::vector<uint8_t> jitter_map;
  int jitter_map_width = 0, jitter_map_height = 0;
  // Drag and paste (Lefebvre ch. 3): the exemplar rectangle (ex_x, ex_y, width, height) is placed
  // with its top-left at (out_x, out_y) of the plane: those pixels copy it verbatim at every level,
  // and correction blends its border into the surroundings. Later pastes win where they overlap.
  struct Paste {
    int ex_x = 0, ex_y = 0, width = 0, height = 0;
    int64_t out_x = 0, out_y = 0;
  };
  std::vector<Paste> pastes;
  int64_t period_x = 0;  // > 0: tileable output of this period (the plane wraps)
  int64_t period_y = 0;
};

// Checks options against the analysis (randomness count and range, passes, period); throws
// proctex::UsageError with a hint.
void check_options(const Analysis& analysis, const SynthOptions& options);

// The coarsest level that is synthesised (levels below it are the constant 0): 1 normally; with a
// period, the first level at which the period is still an even number of pixels.
int first_level(const Analysis& analysis, const SynthOptions& options);

// How many layout shifts the first level draws from (0 = uniform random shifts): layout_shifts,
// at most the exemplar's, and 0 unless their mean correlation reaches layout_min_correlation.
int layout_shift_count(const Analysis& analysis, const SynthOptions& options);

// The correction passes at level l (first_level..L).
int passes_at(const Analysis& analysis, const SynthOptions& options, int level);

// Creates the process's OpenCL runtime and loads the synthesis program (once per process; later
// calls return at once). The command calls it on a second thread at start-up, so that PoCL's
// start-up (it loads LLVM and clang: ~25 ms of CPU) overlaps reading the exemplar and the cached
// analysis. Thread-safe; throws like the Synthesizer would. Loading a program binary silences the
// process's stderr for ~3 ms (kernels/runtime.cpp): the caller must print nothing on stderr until
// it has waited for this call. With PROCTEX_SYNTH_TIMING set (which prints from the calling thread
// meanwhile) only the runtime is created here; the Synthesizer loads the program.
void warm_up();

// Holds the analysis on the device and the built program. One per analysis; not thread-safe.
class Synthesizer {
 public:
  explicit Synthesizer(const Analysis& analysis);
  ~Synthesizer();
  Synthesizer(const Synthesizer&) = delete;
  Synthesizer& operator=(const Synthesizer&) = delete;

  // Exemplar coordinates of every pixel of the window: 2 ints (x, y) per pixel, row-major.
  std::vector<int32_t> synthesise(const Window& window, const SynthOptions& options);

  const Analysis& analysis() const { return analysis_; }

 private:
  struct Device;
  struct DeviceLevel;  // one level's buffers, uploaded on first use
  const DeviceLevel& level(int l, bool correction);
  const Analysis& analysis_;
  std::unique_ptr<Device> device_;
};

}  // namespace proctex::synth
