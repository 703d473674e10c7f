// bench_synth: proctex synth against G'MIC's patch-based synthesis (what users run today) on real
// exemplars from Debian texture packages (bench/synth_exemplars.sh extracts them).
//
//   bench_synth --exemplars DIR [--size 512] [--proctex build/cli/proctex] [--gmic gmic]
//               [--markdown out.md] [--sheet docs/synth-bench.png] [--work DIR] [--big 4096]
//               [--reuse-gmic] [--proctex-args "--passes 3 ..."] [--seeds N] [--runs N]
//
// --seeds N (default 1) also runs both with seeds 2..N (proctex --seed s, gmic -srand s) and adds a
// table of the patch measures averaged over the seeds: one run of each is a sample of a random
// process (G'MIC's grass coherence was 4.99-5.10 over four runs with the same -srand 1).
// --runs N (default 5): timed runs of the proctex command per exemplar (median reported).
//
// --reuse-gmic keeps G'MIC outputs already in the work folder (quality only; its time is then not
// measured, shown as 0, and no speed-up is computed): for iterating on proctex's options.
// --proctex-args adds options to the proctex CLI runs (the in-process timing uses the defaults).
// --big 0 skips the 256^2 analysis and the big output.
//
// For every exemplar (128x128): the time of `proctex synth` as a process (wall and CPU, analysis
// cached) and of the synthesis alone in this process (warm), the time of `gmic EX -srand 1
// -syntexturize_matchpatch S,S -o OUT`, and for both outputs two patch measures on 7x7 RGB patches
// (0-255): coherence = RMS distance of output patches to their nearest exemplar patch,
// completeness = RMS distance of exemplar patches to their nearest output patch; and the project's
// texture similarity (default metric, 128 px crops) to the exemplar; and two repetition measures that
// the patch measures miss (a plain tiling scores 0 on both): the share of output patches that are
// verbatim exemplar patches and the largest piece copied in one (as a share of the exemplar's area).
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "core/error.h"
#include "image/image.h"
#include "kernels/runtime.h"
#include "metrics/metric.h"
#include "synth/analysis.h"
#include "synth/render.h"
#include "synth/synthesis.h"

extern char** environ;

namespace fs = std::filesystem;
using namespace proctex;

namespace {

struct ProcessTime {
  int exit_code = -1;
  double wall = 0, cpu = 0;
  long max_rss_kb = 0;
};

ProcessTime run_process(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  const auto start = std::chrono::steady_clock::now();
  pid_t pid;
  ProcessTime t;
  if (posix_spawnp(&pid, args[0], &fa, nullptr, args.data(), environ) != 0) return t;
  int status = 0;
  struct rusage ru {};
  wait4(pid, &status, 0, &ru);
  t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  t.cpu = ru.ru_utime.tv_sec + ru.ru_utime.tv_usec * 1e-6 + ru.ru_stime.tv_sec + ru.ru_stime.tv_usec * 1e-6;
  t.max_rss_kb = ru.ru_maxrss;
  t.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  posix_spawn_file_actions_destroy(&fa);
  return t;
}

double cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

// 7x7 RGB patches (sRGB codes 0-255) of an image at a stride, one per row.
Eigen::MatrixXf patches(const Image& im, int stride) {
  const int r = 3, D = 7 * 7 * 3;
  std::vector<std::pair<int, int>> at;
  for (int y = r; y + r < im.height; y += stride)
    for (int x = r; x + r < im.width; x += stride) at.emplace_back(x, y);
  Eigen::MatrixXf P(at.size(), D);
  for (size_t i = 0; i < at.size(); ++i) {
    int k = 0;
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        const float* p = im.pixel(at[i].first + dx, at[i].second + dy);
        for (int c = 0; c < 3; ++c) P(i, k++) = 255.0f * linear_to_srgb(std::clamp(p[c], 0.0f, 1.0f));
      }
  }
  return P;
}

// RMS over the rows of Q of the distance to the nearest row of R, per patch value:
// sqrt(mean over queries of min squared distance / D). The nearest row is searched in a 32-D PCA
// space of the exemplar's patches (blocked GEMM), its distance measured exactly in full 147-D.
// `nearest` (optional) receives the index of the nearest row and the squared distance per query.
double nearest_rms(const Eigen::MatrixXf& Q, const Eigen::MatrixXf& R, const Eigen::MatrixXf& basis,
                   const Eigen::RowVectorXf& mean, std::vector<std::pair<int, float>>* nearest = nullptr) {
  const Eigen::MatrixXf q32 = (Q.rowwise() - mean) * basis, r32 = (R.rowwise() - mean) * basis;
  const Eigen::VectorXf rn = r32.rowwise().squaredNorm();
  double total = 0;
  const int block = 256;
  if (nearest) nearest->resize(Q.rows());
  for (int b = 0; b < q32.rows(); b += block) {
    const int n = std::min<int>(block, q32.rows() - b);
    const Eigen::MatrixXf cross = q32.middleRows(b, n) * r32.transpose();  // n x |R|
    for (int i = 0; i < n; ++i) {
      Eigen::Index arg;
      (rn.transpose() - 2.0f * cross.row(i)).minCoeff(&arg);
      const float d = (Q.row(b + i) - R.row(arg)).squaredNorm();
      total += d;
      if (nearest) (*nearest)[b + i] = {static_cast<int>(arg), d};
    }
  }
  return std::sqrt(total / Q.rows() / Q.cols());
}

struct Quality {
  double coherence = 0, completeness = 0, similarity = 0;
  // Repetition: output patches (7x7, on a 4 px grid) that are verbatim exemplar patches (RMS < 1
  // code) are grouped into pieces: grid neighbours copying from the same offset (exemplar position
  // minus output position, modulo the exemplar). `copied` = share of the grid that is verbatim;
  // `piece` = the largest piece's area as a share of the exemplar's (1 = a whole exemplar copied in
  // one piece; a plain tiling scores the whole output).
  double copied = 0, piece = 0;
};

Quality quality(const Image& exemplar, const Image& output) {
  Quality q;
  const Eigen::MatrixXf ex = patches(exemplar, 1);
  const Eigen::RowVectorXf mean = ex.colwise().mean();
  const Eigen::MatrixXf centred = ex.rowwise() - mean;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXf> es(centred.transpose() * centred);
  const Eigen::MatrixXf basis = es.eigenvectors().rightCols(32);
  std::vector<std::pair<int, float>> nearest;
  q.coherence = nearest_rms(patches(output, 4), ex, basis, mean, &nearest);  // output patches on a 4-px grid
  {
    // The grid of patches(output, 4): centres x = 3 + 4i, y = 3 + 4j; exemplar patches(ex, 1): row-major
    // centres (3 + k % (ew - 6), 3 + k / (ew - 6)).
    int cols = 0, rows = 0;
    for (int x = 3; x + 3 < output.width; x += 4) ++cols;
    for (int y = 3; y + 3 < output.height; y += 4) ++rows;
    const int ew = exemplar.width, eh = exemplar.height, pw = ew - 6;
    std::vector<int> offset(static_cast<size_t>(cols) * rows, -1);  // -1 = not verbatim
    int verbatim = 0;
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < cols; ++i) {
        const auto [k, d] = nearest[static_cast<size_t>(j) * cols + i];
        if (d / (7 * 7 * 3) >= 1.0f) continue;
        const int ux = 3 + k % pw, uy = 3 + k / pw;
        const int ox = ((ux - (3 + 4 * i)) % ew + ew) % ew, oy = ((uy - (3 + 4 * j)) % eh + eh) % eh;
        offset[static_cast<size_t>(j) * cols + i] = oy * ew + ox;
        ++verbatim;
      }
    q.copied = double(verbatim) / offset.size();
    std::vector<char> seen(offset.size(), 0);
    size_t largest = 0;
    for (size_t s0 = 0; s0 < offset.size(); ++s0) {
      if (offset[s0] < 0 || seen[s0]) continue;
      std::vector<size_t> stack{s0};
      seen[s0] = 1;
      size_t count = 0;
      while (!stack.empty()) {
        const size_t c = stack.back();
        stack.pop_back();
        ++count;
        const int i = static_cast<int>(c % cols), j = static_cast<int>(c / cols);
        const int nb[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
        for (const auto& n : nb) {
          if (n[0] < 0 || n[1] < 0 || n[0] >= cols || n[1] >= rows) continue;
          const size_t m = static_cast<size_t>(n[1]) * cols + n[0];
          if (!seen[m] && offset[m] == offset[c]) seen[m] = 1, stack.push_back(m);
        }
      }
      largest = std::max(largest, count);
    }
    q.piece = double(largest) * 16.0 / (double(ew) * eh);
  }
  // Every exemplar patch against EVERY patch of the output's central 256x256 (a patch grid would
  // miss verbatim copies that sit off the grid: a 2 px grid gave G'MIC 12.3, a 3 px grid 1.2).
  const int cw = std::min(256, output.width), ch = std::min(256, output.height);
  const Image centre = crop(output, (output.width - cw) / 2, (output.height - ch) / 2, cw, ch);
  q.completeness = nearest_rms(ex, patches(centre, 1), basis, mean);
  // Texture similarity at the exemplar's scale: 128 px crops of the output (4 corners averaged).
  const auto& m = metrics::default_metric();
  const int res = std::min(exemplar.width, exemplar.height) / 16 * 16;
  const auto fe = m.features(exemplar, res);
  double s = 0;
  const int c = res;
  for (int k = 0; k < 4; ++k) {
    const int x = (k % 2) * (output.width - c), y = (k / 2) * (output.height - c);
    s += m.similarity(fe, m.features(crop(output, x, y, c, c), res));
  }
  q.similarity = s / 4;
  return q;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  fs::path exemplar_dir, work = "build/bench-synth", markdown, sheet;
  std::string proctex_bin = "build/cli/proctex", gmic = "gmic";
  int size = 512, big = 4096, seeds = 1, runs = 5;
  bool reuse_gmic = false;
  std::vector<std::string> extra_args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--exemplars") exemplar_dir = next();
    else if (a == "--work") work = next();
    else if (a == "--markdown") markdown = next();
    else if (a == "--sheet") sheet = next();
    else if (a == "--proctex") proctex_bin = next();
    else if (a == "--gmic") gmic = next();
    else if (a == "--size") size = std::stoi(next());
    else if (a == "--big") big = std::stoi(next());
    else if (a == "--reuse-gmic") reuse_gmic = true;
    else if (a == "--seeds") seeds = std::max(1, std::stoi(next()));
    else if (a == "--runs") runs = std::max(1, std::stoi(next()));
    else if (a == "--proctex-args") {
      std::istringstream words(next());
      for (std::string w; words >> w;) extra_args.push_back(w);
    }
    else {
      std::fprintf(stderr, "usage: bench_synth --exemplars DIR [--size 512] [--big 4096] [--gmic gmic] "
                           "[--proctex build/cli/proctex] [--markdown out.md] [--sheet out.png] [--work DIR] [--seeds N] [--runs N]\n");
      return 2;
    }
  }
  if (exemplar_dir.empty()) {
    std::fprintf(stderr, "bench_synth: --exemplars DIR is required (bench/synth_exemplars.sh DIR makes it)\n");
    return 2;
  }
  try {
    fs::create_directories(work);
    // G'MIC's OpenMP threads spin-wait by default: on a machine with any other load that spin is
    // counted as CPU and wall (brick: 16.5 s CPU against 0.86 s passive in the same minute, load
    // ~2.7). Passive waiting measures its work, not the contention (proctex does not use OpenMP).
    setenv("OMP_WAIT_POLICY", "passive", 0);
    const fs::path cache = work / "cache";
    setenv("PROCTEX_CACHE_DIR", cache.c_str(), 1);
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(exemplar_dir))
      if (e.path().extension() == ".png") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    std::string table =
        "| exemplar | proctex CLI wall / CPU (s) | proctex synthesis in-process wall / CPU (s) | G'MIC wall / CPU (s) "
        "| speed-up (CPU, CLI) | speed-up (wall, CLI) | coherence proctex / G'MIC | completeness proctex / G'MIC | similarity proctex / G'MIC "
        "| verbatim share proctex / G'MIC | largest copied piece proctex / G'MIC |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n";
    std::vector<double> coh_p, coh_g, com_p, com_g, sim_p, sim_g, speed_cli, speed_wall, speed_lib, cop_p, cop_g, pie_p, pie_g;
    std::vector<Image> tiles;
    std::vector<std::string> labels;
    for (const auto& file : files) {
      const std::string name = file.stem().string();
      synth::Exemplar ex;
      ex.name = name;
      ex.colour = synth::load_exemplar_image(file);
      const fs::path out_p = work / (name + "_proctex.png"), out_g = work / (name + "_gmic.png");
      const std::string sz = std::to_string(size);
      // CLI as a user runs it (the first call analyses and fills the cache; time the second).
      std::vector<std::string> cmd = {proctex_bin, "-q", "synth", file.string(), "-o", out_p.string(), "--size", sz};
      cmd.insert(cmd.end(), extra_args.begin(), extra_args.end());
      run_process(cmd);
      std::vector<double> cli_wall, cli_cpu;
      for (int r = 0; r < runs; ++r) {
        const auto t = run_process(cmd);
        if (t.exit_code != 0) throw Error("proctex synth failed on " + file.string());
        cli_wall.push_back(t.wall), cli_cpu.push_back(t.cpu);
      }
      // In-process synthesis (analysis cached, program built): what a server or a pipeline pays.
      // Median of 3.
      const synth::Analysis an = synth::analyse_cached(ex, {}, cache);
      synth::Synthesizer s(an);
      s.synthesise({0, 0, size, size}, {});
      std::vector<double> lib_wall, lib_cpu;
      for (int r = 0; r < 3; ++r) {
        const double c0 = cpu_seconds();
        const auto t0 = std::chrono::steady_clock::now();
        s.synthesise({0, 0, size, size}, {});
        lib_wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        lib_cpu.push_back(cpu_seconds() - c0);
      }
      // G'MIC, same size, its default threads (all cores, like PoCL); one run (it takes seconds).
      std::vector<double> g_wall, g_cpu;
      for (int r = 0; r < (reuse_gmic && fs::exists(out_g) ? 0 : 1); ++r) {
        const auto t = run_process({gmic, file.string(), "-srand", "1", "-syntexturize_matchpatch", sz + "," + sz,
                                    "-o", out_g.string()});
        if (t.exit_code != 0) throw Error("gmic failed on " + file.string(), "install it: apt-get install gmic");
        g_wall.push_back(t.wall), g_cpu.push_back(t.cpu);
      }
      const Image ip = load_image(out_p), ig = load_image(out_g);
      const Quality qp = quality(ex.colour, ip);
      Quality qg;
      // With --reuse-gmic, G'MIC's measures are computed once and kept beside its output.
      const fs::path qfile = work / (name + "_gmic.quality");
      bool cached = false;
      if (reuse_gmic && g_cpu.empty() && fs::exists(qfile)) {
        std::ifstream in(qfile);
        cached = static_cast<bool>(in >> qg.coherence >> qg.completeness >> qg.similarity >> qg.copied >> qg.piece);
      }
      if (!cached) {
        qg = quality(ex.colour, ig);
        std::ofstream(qfile) << fmt::format("{:.9g} {:.9g} {:.9g} {:.9g} {:.9g}\n", qg.coherence, qg.completeness,
                                            qg.similarity, qg.copied, qg.piece);
      }
      coh_p.push_back(qp.coherence), coh_g.push_back(qg.coherence);
      com_p.push_back(qp.completeness), com_g.push_back(qg.completeness);
      sim_p.push_back(qp.similarity), sim_g.push_back(qg.similarity);
      cop_p.push_back(qp.copied), cop_g.push_back(qg.copied), pie_p.push_back(qp.piece), pie_g.push_back(qg.piece);
      speed_cli.push_back(median(g_cpu) / median(cli_cpu));
      speed_wall.push_back(median(g_wall) / median(cli_wall));
      speed_lib.push_back(median(g_cpu) / median(lib_cpu));
      table += fmt::format("| {} | {:.3f} / {:.3f} | {:.3f} / {:.3f} | {:.2f} / {:.2f} | {:.1f}x | {:.1f}x | {:.2f} / {:.2f} | "
                           "{:.2f} / {:.2f} | {:.3f} / {:.3f} | {:.2f} / {:.2f} | {:.2f} / {:.2f} |\n",
                           name, median(cli_wall), median(cli_cpu), median(lib_wall), median(lib_cpu), median(g_wall),
                           median(g_cpu), median(g_cpu) / median(cli_cpu), median(g_wall) / median(cli_wall), qp.coherence, qg.coherence,
                           qp.completeness, qg.completeness, qp.similarity, qg.similarity, qp.copied, qg.copied,
                           qp.piece, qg.piece);
      std::fprintf(stderr, "%s", table.substr(table.rfind("| " + name)).c_str());
      // Side by side at 2x: exemplar, a 128 px crop of each output.
      const int c = ex.colour.width;
      tiles.push_back(resize(ex.colour, 2 * c, 2 * c));
      tiles.push_back(resize(crop(ip, 0, 0, c, c), 2 * c, 2 * c));
      tiles.push_back(resize(crop(ig, 0, 0, c, c), 2 * c, 2 * c));
      labels.push_back(name + " (exemplar)");
      labels.push_back("proctex");
      labels.push_back("G'MIC");
    }
    table += fmt::format(
        "| **median** | | | | CLI {:.1f}x, in-process {:.1f}x | CLI {:.1f}x | {:.2f} / {:.2f} | {:.2f} / {:.2f} | {:.3f} / {:.3f} "
        "| {:.2f} / {:.2f} | {:.2f} / {:.2f} |\n",
        median(speed_cli), median(speed_lib), median(speed_wall), median(coh_p), median(coh_g), median(com_p), median(com_g),
        median(sim_p), median(sim_g), median(cop_p), median(cop_g), median(pie_p), median(pie_g));

    // Seeds 2..N of both: one output per seed is one sample of a random process, so the verdict on
    // the patch measures rests on their average over the seeds.
    std::string seed_table;
    if (seeds > 1) {
      seed_table = fmt::format(
          "\nPatch measures averaged over seeds 1-{} (proctex `--seed s`, G'MIC `-srand s`):\n\n"
          "| exemplar | coherence proctex / G'MIC | completeness proctex / G'MIC | largest copied piece proctex / G'MIC "
          "|\n|---|---|---|---|\n",
          seeds);
      std::vector<double> mean_coh_p, mean_coh_g, mean_com_p, mean_com_g, mean_pie_p, mean_pie_g;
      std::vector<std::vector<double>> seed_coh_p(seeds), seed_coh_g(seeds);
      for (size_t f = 0; f < files.size(); ++f) {
        const fs::path& file = files[f];
        const std::string name = file.stem().string(), sz = std::to_string(size);
        const Image exemplar = synth::load_exemplar_image(file);
        double cp = coh_p[f], cg = coh_g[f], mp = com_p[f], mg = com_g[f], pp = pie_p[f], pg = pie_g[f];
        seed_coh_p[0].push_back(coh_p[f]), seed_coh_g[0].push_back(coh_g[f]);
        for (int sd = 2; sd <= seeds; ++sd) {
          const fs::path out_p = work / fmt::format("{}_proctex_s{}.png", name, sd),
                         out_g = work / fmt::format("{}_gmic_s{}.png", name, sd);
          std::vector<std::string> cmd = {proctex_bin, "-q",     "synth",   file.string(),       "-o",
                                          out_p.string(), "--size", sz, "--seed", std::to_string(sd)};
          cmd.insert(cmd.end(), extra_args.begin(), extra_args.end());
          if (run_process(cmd).exit_code != 0) throw Error("proctex synth failed on " + file.string());
          if (!(reuse_gmic && fs::exists(out_g)) &&
              run_process({gmic, file.string(), "-srand", std::to_string(sd), "-syntexturize_matchpatch",
                           sz + "," + sz, "-o", out_g.string()})
                      .exit_code != 0)
            throw Error("gmic failed on " + file.string(), "install it: apt-get install gmic");
          const Quality qp = quality(exemplar, load_image(out_p)), qg = quality(exemplar, load_image(out_g));
          cp += qp.coherence, cg += qg.coherence, mp += qp.completeness, mg += qg.completeness;
          pp += qp.piece, pg += qg.piece;
          seed_coh_p[sd - 1].push_back(qp.coherence), seed_coh_g[sd - 1].push_back(qg.coherence);
        }
        const double n = seeds;
        mean_coh_p.push_back(cp / n), mean_coh_g.push_back(cg / n), mean_com_p.push_back(mp / n);
        mean_com_g.push_back(mg / n), mean_pie_p.push_back(pp / n), mean_pie_g.push_back(pg / n);
        seed_table += fmt::format("| {} | {:.2f} / {:.2f} | {:.2f} / {:.2f} | {:.2f} / {:.2f} |\n", name, cp / n,
                                  cg / n, mp / n, mg / n, pp / n, pg / n);
        std::fprintf(stderr, "%s", seed_table.substr(seed_table.rfind("| " + name)).c_str());
      }
      seed_table += fmt::format("| **median** | {:.2f} / {:.2f} | {:.2f} / {:.2f} | {:.2f} / {:.2f} |\n",
                                median(mean_coh_p), median(mean_coh_g), median(mean_com_p), median(mean_com_g),
                                median(mean_pie_p), median(mean_pie_g));
      seed_table += "\nMedian coherence per seed, proctex / G'MIC:";
      for (int sd = 0; sd < seeds; ++sd)
        seed_table += fmt::format(" seed {}: {:.2f} / {:.2f};", sd + 1, median(seed_coh_p[sd]), median(seed_coh_g[sd]));
      seed_table += "\n";
    }

    // Analysis of a 256^2 exemplar (no cache), and a big output window by window.
    std::string extra;
    if (!files.empty() && big > 0) {
      synth::Exemplar ex;
      ex.colour = resize(synth::load_exemplar_image(files.front()), 256, 256);
      std::vector<double> times;
      for (int r = 0; r < 3; ++r) times.push_back(synth::analyse(ex).seconds);
      extra += fmt::format("- analysis of a 256x256 exemplar ({} enlarged), no cache: median {:.3f} s wall\n",
                           files.front().stem().string(), median(times));
      if (big > 0) {
        const fs::path out = work / "big.png";
        const auto t = run_process({proctex_bin, "-q", "synth", files.front().string(), "-o", out.string(), "--size",
                                    std::to_string(big)});
        extra += fmt::format("- `proctex synth {} -o big.png --size {}` (analysis cached): {:.2f} s wall, {:.2f} s CPU, "
                             "peak memory {:.0f} MB{}\n",
                             files.front().filename().string(), big, t.wall, t.cpu, t.max_rss_kb / 1024.0,
                             t.exit_code == 0 ? "" : " (FAILED)");
      }
    }
    const std::string device = ocl::Runtime::instance().device().name;
    const std::string report = table + seed_table + "\n" + extra + fmt::format("- device: {}\n", device);
    std::printf("%s", report.c_str());
    if (!markdown.empty()) std::ofstream(markdown) << report;
    if (!sheet.empty() && !tiles.empty()) save_image(contact_sheet(tiles, labels, 6, 256), sheet);
  } catch (const Error& e) {
    std::fprintf(stderr, "bench_synth: %s (%s)\n", e.message().c_str(), e.hint().c_str());
    return 1;
  }
  return 0;
}
