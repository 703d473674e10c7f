#pragma once
// proctex match over many photos: a folder (recursive) or a list file, optionally one shard of it.
//   proctex match photos/ --out-dir results/ [--shard 2/4]
// One result JSON per photo (results/<relative path with / as __>.json), an index (index.csv and
// index.json; index-i-of-n.* for a shard) with shader, similarity and verdict per photo.
// Resumable: a photo whose result file records the same photo hash, match options and catalogue is
// skipped (its stored result goes into the index). A photo that fails (unreadable, too small) gets
// an error result and an index row; the batch goes on, and the command exits 1 at the end.
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli/commands.h"
#include "search/match.h"

namespace proctex::cli {

struct MatchBatchCli {
  std::string out_dir;       // --out-dir (default: ./proctex-match)
  std::string shard = "1/1";  // --shard i/n over the sorted photo list
  bool force = false;        // --force: redo photos whose result is current
  CLI::App* match = nullptr;  // the match command (set by add_match_batch_options): single-photo options given?
};

// Adds --out-dir, --shard, --force (and a footer paragraph) to `proctex match`.
void add_match_batch_options(CLI::App& match, MatchBatchCli& batch);

// True when `input` is a folder or a list file (.txt, .lst, .list: one photo path per line,
// relative to the list's folder, '#' comments), or when --out-dir was given.
bool is_match_batch(const std::string& input, const MatchBatchCli& batch);

// The photos of a folder (recursive, image extensions, sorted) or a list file, as given paths and
// their names relative to the folder / as listed. `skip` (the output folder) is left out.
struct BatchPhoto {
  std::filesystem::path path;
  std::string name;  // relative name, '/' separated
};
std::vector<BatchPhoto> list_batch_photos(const std::string& input, const std::filesystem::path& skip = {});

// Runs the batch; `fingerprint` is what makes a stored result current besides the photo and the
// catalogue (the match options and the crop).
void run_match_batch(const std::string& input, const std::string& crop, const std::string& db,
                     const search::MatchOptions& options, const MatchBatchCli& batch, bool json,
                     const GlobalOptions& global);

}  // namespace proctex::cli
