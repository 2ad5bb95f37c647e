#include "bench/report/trial_records_file.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "calib/common/errors.h"

namespace twin {
namespace {

std::string Temp(const std::string& name) {
  const std::string p = ::testing::TempDir() + "/trials_file_" + name + ".jsonl";
  std::filesystem::remove(p);
  return p;
}

TrialRecord Record(nlohmann::json j) { return TrialRecord(std::move(j)); }

TEST(TrialsFileTest, AppendsCompleteLinesAndReadsThemBack) {
  const std::string path = Temp("append");
  EXPECT_TRUE(ReadTrialsFile(path).records.empty());  // missing: empty
  AppendTrialRecord(path, Record({{"trial", 3}, {"status", "ok"}}));
  AppendTrialRecord(path, Record({{"trial", 1}, {"status", "failed"}, {"reason", "x\ny"}}));
  const TrialsFileContent c = ReadTrialsFile(path);
  ASSERT_EQ(c.records.size(), 2u);
  EXPECT_EQ(c.records[0].trial(), 3);
  EXPECT_EQ(c.records[1].document()["reason"], "x\ny");  // a newline in it stays escaped
  EXPECT_FALSE(c.torn_tail);
  EXPECT_EQ(c.valid_bytes, std::filesystem::file_size(path));
}

TEST(TrialsFileTest, ATornLastLineIsDroppedAndCutOff) {
  const std::string path = Temp("torn");
  AppendTrialRecord(path, Record({{"trial", 0}}));
  const std::size_t good = std::filesystem::file_size(path);
  std::ofstream(path, std::ios::app) << "{\"trial\": 1, \"figu";  // killed mid-line
  const TrialsFileContent c = ReadTrialsFile(path);
  EXPECT_TRUE(c.torn_tail);
  ASSERT_EQ(c.records.size(), 1u);
  EXPECT_EQ(c.valid_bytes, good);
  TruncateTrialsFile(path, c.valid_bytes);
  AppendTrialRecord(path, Record({{"trial", 1}}));
  const TrialsFileContent d = ReadTrialsFile(path);
  EXPECT_FALSE(d.torn_tail);
  ASSERT_EQ(d.records.size(), 2u);
  EXPECT_EQ(d.records[1].trial(), 1);
}

TEST(TrialsFileTest, ABrokenLineInsideTheFileIsAnErrorNamingItsLine) {
  const std::string path = Temp("broken");
  std::ofstream(path) << "{\"trial\": 0}\nnot json\n{\"trial\": 2}\n";
  try {
    ReadTrialsFile(path);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":2"), std::string::npos) << e.what();
  }
  std::ofstream(path) << "{\"trial\": 0}\n{\"status\": \"ok\"}\n";
  try {
    ReadTrialsFile(path);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace twin
