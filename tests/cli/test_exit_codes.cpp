// The exit-code table (cli/exit_codes.h): what `penumbra exit-codes` prints,
// the --help footer made from it, and the codes the commands return.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/exit_codes.h"
#include "cli_test.h"

namespace penumbra {
namespace {

TEST(ExitCodes, JsonListsEveryCodeWithNameAndMeaning) {
  const CliResult r = run_penumbra({"exit-codes", "--json"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  const nlohmann::json list = nlohmann::json::parse(r.out);
  ASSERT_TRUE(list.is_array());
  std::set<int> codes;
  for (const nlohmann::json& row : list) {
    ASSERT_EQ(row.size(), 3u) << row.dump();
    EXPECT_TRUE(row["code"].is_number_integer()) << row.dump();
    EXPECT_FALSE(row["name"].get<std::string>().empty()) << row.dump();
    EXPECT_FALSE(row["meaning"].get<std::string>().empty()) << row.dump();
    codes.insert(row["code"].get<int>());
  }
  EXPECT_EQ(codes, (std::set<int>{0, 1, 2, 3, 128}));
  EXPECT_EQ(list.back()["meaning"].get<std::string>().rfind("128+N: stopped by signal N", 0), 0u)
      << list.back().dump();
}

TEST(ExitCodes, TextListsEveryRowAndHelpEndsWithTheSameTable) {
  const CliResult r = run_penumbra({"exit-codes"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  for (const ExitCodeInfo& info : kExitCodes) {
    EXPECT_NE(r.out.find(std::string(info.name)), std::string::npos) << info.name;
    EXPECT_NE(r.out.find(std::string(info.meaning)), std::string::npos) << info.name;
  }
  // The sentence every --help ends with, as it read before the table existed.
  EXPECT_EQ(exit_status_text(),
            "Exit status: 0 success; 1 a run failed (renderer or internal error, NaN or Inf in a "
            "render); 2 bad input (usage, scene or study file, output path, a render over "
            "--max-memory); 3 a comparison missed its bound or an image holds NaN/Inf (compare, "
            "calibrate); 128+N stopped by signal N (130 Ctrl-C, 143 SIGTERM), nothing "
            "half-written.");
  const CliResult help = run_penumbra({"exit-codes", "--help"});
  EXPECT_NE(help.out.find(exit_status_text()), std::string::npos) << help.out;
}

TEST(ExitCodes, ExceptionsMapToTheTablesCodes) {
  EXPECT_EQ(run_penumbra({"exit-codes", "--no-such-option"}).code, kExitBadInput);
  EXPECT_EQ(run_penumbra({"status", "/nonexistent/penumbra-folder"}).code, kExitBadInput);
  EXPECT_EQ(run_penumbra({"compare", "/nonexistent/a.exr", "/nonexistent/b.exr"}).code,
            kExitBadInput);
}

}  // namespace
}  // namespace penumbra
