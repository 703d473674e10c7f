// The labelled real-texture set (bench/realset/labels.json, docs/realset.md) is the yardstick of
// `proctex match` and the training data of its shader selection: a label naming a shader the
// library does not have, a duplicated id or a photo moved between the splits would silently change
// the numbers in docs/match-evaluation.md. These tests check the file, not the images (those are
// fetched by bench/realset/build.py).
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "shaders/library.h"

namespace proctex {
namespace {

const nlohmann::json& labels() {
  static const nlohmann::json j = [] {
    std::ifstream in(std::string(PROCTEX_SOURCE_DIR) + "/bench/realset/labels.json");
    return nlohmann::json::parse(in);
  }();
  return j;
}

TEST(RealsetLabels, EveryItemIsCompleteAndItsIdIsUnique) {
  std::set<std::string> ids;
  const std::regex hex("[0-9a-f]{64}");
  for (const auto& item : labels()["images"]) {
    for (const char* key : {"id", "package", "version", "path", "licence", "kind", "accepted", "split", "sha256"})
      ASSERT_TRUE(item.contains(key)) << key << " missing in " << item.dump();
    EXPECT_TRUE(ids.insert(item["id"].get<std::string>()).second) << "duplicate id " << item["id"];
    EXPECT_TRUE(std::regex_match(item["sha256"].get<std::string>(), hex)) << item["id"];
    EXPECT_TRUE(item["split"] == "tune" || item["split"] == "report") << item["id"];
    EXPECT_FALSE(item["licence"].get<std::string>().empty()) << item["id"];
    if (item.contains("crop")) {
      ASSERT_EQ(item["crop"].size(), 3u) << item["id"];
      EXPECT_GE(item["crop"][2].get<int>(), 256) << item["id"] << ": photos are at least 256 px, never rescaled";
    }
  }
  EXPECT_GE(ids.size(), 188u);
}

TEST(RealsetLabels, AcceptedShadersExistAndMatchTheirKind) {
  const auto& library = ShaderLibrary::builtin();
  const auto& kinds = labels()["kinds"];
  for (const auto& [kind, shaders] : kinds.items())
    for (const auto& s : shaders) EXPECT_NE(library.find(s.get<std::string>()), nullptr) << kind << ": " << s;
  for (const auto& item : labels()["images"]) {
    const std::string kind = item["kind"];
    ASSERT_TRUE(kinds.contains(kind)) << item["id"];
    EXPECT_EQ(item["accepted"], kinds[kind]) << item["id"] << ": the accepted set is the kind's";
  }
}

// The report split is held out: 43 photos of the first batch, so that numbers stay comparable
// across sessions; later additions (batches 2-5: docs/realset.md) go to tune only.
TEST(RealsetLabels, TheReportSplitIsTheFirstBatchsFortyThree) {
  std::map<std::string, int> report_per_kind;
  int report = 0, added = 0;
  for (const auto& item : labels()["images"]) {
    const bool added_later = item.value("batch", 1) >= 2;
    if (added_later) {
      ++added;
      EXPECT_EQ(item["split"], "tune") << item["id"] << ": added photos are tune only";
    }
    if (item["split"] == "report") {
      ++report;
      ++report_per_kind[item["kind"].get<std::string>()];
    }
  }
  EXPECT_EQ(report, 43);
  EXPECT_GE(added, 80);
  EXPECT_EQ(report_per_kind.size(), labels()["kinds"].size()) << "every kind is in the report split";
}

}  // namespace
}  // namespace proctex
