#include "bench/report/study_file.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "calib/common/errors.h"

namespace twin {
namespace {

std::string Temp(const std::string& name) {
  const std::string p = ::testing::TempDir() + "/study_file_" + name + ".json";
  std::filesystem::remove(p);
  return p;
}

TEST(StudyFileTest, WritesEveryKeyAndReadsTheIdentityBack) {
  const std::string path = Temp("round");
  EXPECT_FALSE(ReadStudyFile(path));  // none yet
  const std::string text = StudyFileText({"/s/study.yaml", "study_small", "00ff", 8, "1/4"});
  // Keys sorted (nlohmann's object), two-space indent, a final newline.
  EXPECT_EQ(text, "{\n  \"scenario\": \"study_small\",\n  \"scenario_file\": \"/s/study.yaml\",\n"
                  "  \"scenario_hash\": \"00ff\",\n  \"shard\": \"1/4\",\n  \"trials\": 8\n}\n");
  std::ofstream(path) << text;
  const std::optional<StudyFileIdentity> id = ReadStudyFile(path);
  ASSERT_TRUE(id);
  EXPECT_EQ(id->scenario_hash, "00ff");
  EXPECT_EQ(id->shard, "1/4");
  std::ofstream(path) << R"({"shard": "0/1"})";
  EXPECT_FALSE(ReadStudyFile(path)->scenario_hash);  // absent: no hash
}

TEST(StudyFileTest, AFileThatIsNoStudyFileIsAnInputError) {
  const std::string path = Temp("bad");
  for (const char* text : {"not json", "[1]", R"({"scenario_hash": 3})"}) {
    std::ofstream(path) << text;
    EXPECT_THROW(ReadStudyFile(path), InputError) << text;
  }
}

}  // namespace
}  // namespace twin
