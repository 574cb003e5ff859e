// The dataset/classifier/ensemble commands composed like a shell experiment: files in, files out.

#include <algorithm>
#include <array>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>
#include <sys/wait.h>

#include "cli_runner.hpp"
#include "ml_test_data.hpp"
#include "multicue/ml/dataset.hpp"
#include "multicue/ml/serialization.hpp"
#include "test_util.hpp"

namespace multicue::ml {
namespace {

using test::CliResult;
using test::RunCli;

TEST(MlCli, ComposesDatasetClassifierAndEnsembleCommands) {
    test::TempDir dir;
    const auto p = [&](const std::string& n) { return (dir / n).string(); };
    SaveCsv(test::Blobs(3, 8, 2, 6, 0.4f, 3, 2), p("all.csv"));
    auto ok = [&](const std::string& args) {
        const CliResult r = RunCli(args);
        EXPECT_EQ(r.code, 0) << args << "\n" << r.output;
        return r.output;
    };
    EXPECT_NE(ok("dataset info " + p("all.csv")).find("48 rows, 6 columns, 24 instances"),
              std::string::npos);
    ok("dataset convert " + p("all.csv") + " " + p("all.mcd"));
    ok("dataset split " + p("all.mcd") + " --method three-way -o " + p("s"));
    ok("dataset normalise " + p("s_level0.mcd") + " --save " + p("n.mcx") + " -o " + p("l0.mcd"));
    ok("dataset normalise " + p("s_level1.mcd") + " --apply " + p("n.mcx") + " -o " + p("l1.mcd"));
    ok("dataset normalise " + p("s_test.mcd") + " --apply " + p("n.mcx") + " -o " + p("t.mcd"));
    ok("classifier train " + p("l0.mcd") + " --spec knn:k=3 -o " + p("knn.mcm"));
    const std::string eval = ok("classifier eval " + p("knn.mcm") + " " + p("t.mcd") +
                                " --confusion-image " + p("c.ppm"));
    EXPECT_NE(eval.find("accuracy 1.0000"), std::string::npos) << eval;
    ok("classifier predict " + p("knn.mcm") + " " + p("t.mcd") + " -o " + p("conf.csv"));
    ok("dataset select " + p("all.mcd") + " --blocks b0 -o " + p("b0.mcd"));
    ok("dataset select " + p("all.mcd") + " --drop-blocks b0 -o " + p("b12.mcd"));
    EXPECT_NE(ok("dataset concat " + p("b0.mcd") + " " + p("b12.mcd") + " -o " + p("re.mcd") +
                 " && echo joined")
                  .find("joined"),
              std::string::npos);
    EXPECT_EQ(ReadBytes(p("re.mcd")), ReadBytes(p("all.mcd")));
    ok("dataset relabel " + p("all.mcd") + " --depth 1 -o " + p("flat.mcd"));
    EXPECT_NE(ok("dataset info " + p("flat.mcd")).find("2 classes"), std::string::npos);
    ok("ensemble train " + p("l0.mcd") + " " + p("l1.mcd") +
       " --member knn:k=3 --subsets singles+doubles --level1 svm:kernel=linear -o " + p("e.mce"));
    const std::string ens = ok("ensemble eval " + p("e.mce") + " " + p("t.mcd"));
    EXPECT_NE(ens.find("rule   stacking"), std::string::npos) << ens;
    EXPECT_NE(ens.find("member b0+b1"), std::string::npos) << ens;
    ok("classifier cv " + p("all.mcd") + " --spec knn:k=3 --k 3 --by-group");

    // Errors: one line, non-zero exit, no output file.
    CliResult r = RunCli("classifier train " + p("l0.mcd") + " --spec knn:k=0 -o " + p("bad.mcm"));
    EXPECT_EQ(r.code, 2) << r.output;
    r = RunCli("classifier eval " + p("knn.mcm") + " " + p("b0.mcd"));
    EXPECT_EQ(r.code, 2) << r.output;  // 2 columns instead of 6
    EXPECT_NE(r.output.find("trained on 6 features, got 2"), std::string::npos) << r.output;
    WriteBytesAtomically(p("junk.mcm"), "MCUEMODL garbage");
    r = RunCli("classifier eval " + p("junk.mcm") + " " + p("t.mcd"));
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    r = RunCli("dataset info " + p("missing.mcd"));
    EXPECT_EQ(r.code, 1) << r.output;
}

}  // namespace
}  // namespace multicue::ml
