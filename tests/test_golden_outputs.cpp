// Golden outputs: every file the program writes -- report.json, report.html, every image, the JUnit
// XML, the --json summary -- for the demo, the examples, a glTF level and a Quake 3 map, hashed and
// compared with tests/golden/CASE.sha1. A refactor proves itself here: it must leave every hash as
// it was. The runs set VISAUDIT_FIXED_TIMINGS=1 (render/stopwatch.h), so timing fields read 0 and
// whole files compare byte for byte.
//
// A change that is meant to change outputs regenerates the manifests and says so in its commit:
//   VISAUDIT_UPDATE_GOLDEN=1 build/tests/visaudit_tests --gtest_filter='Golden*'
// On a mismatch the test lists the files that differ and copies the run's folder to
// BUILD/tests/golden-actual/CASE for a look (with the manifest it would write, CASE.sha1).
#include <gtest/gtest.h>
#include <unistd.h>

#include <OpenImageIO/hash.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "tests/run_binary.h"

namespace fs = std::filesystem;
using va::testing_util::runBinary;
using va::testing_util::slurpFile;

namespace {

struct GoldenCase {
    const char *name;
    // Commands run in order from the source folder (paths stay relative, so the manifest does not
    // depend on where the checkout is). "{OUT}" is the case's output folder.
    std::vector<std::vector<std::string>> commands;
    const char *needs = nullptr;  // a data file the case needs (skipped when absent)
};

const std::string kThor = "data/openarena/pak6-patch088.pk3:maps/oa_thor.bsp";

std::vector<GoldenCase> goldenCases() {
    return {
        {"demo", {{"analyze", "--out", "{OUT}/report", "--quiet", "--json"}}},
        {"hall", {{"analyze", "examples/hall.scene.json", "--out", "{OUT}/report", "--quiet"}}},
        {"hall_views",
         {{"analyze", "examples/hall.scene.json", "--views", "examples/hall.views.json", "--out", "{OUT}/report",
           "--quiet"}}},
        {"rooms", {{"analyze", "examples/rooms.scene.json", "--out", "{OUT}/report", "--quiet"}}},
        {"check_demo",
         {{"check", "--budget", "examples/demo.budget.json", "--out", "{OUT}/report", "--junit", "{OUT}/junit.xml",
           "--quiet"}}},
        {"merge_hall",
         {{"analyze", "examples/hall.scene.json", "--views", "examples/hall.views.json", "--shard", "1/2", "--out",
           "{OUT}/s1", "--quiet"},
          {"analyze", "examples/hall.scene.json", "--views", "examples/hall.views.json", "--shard", "2/2", "--out",
           "{OUT}/s2", "--quiet"},
          {"merge", "{OUT}/s1", "{OUT}/s2", "--out", "{OUT}/merged", "--quiet"}}},
        {"depth_audit", {{"depth-audit", "--near", "0.1", "--far", "1000", "--out", "{OUT}/depth"}}},
        {"dungeon",
         {{"analyze", "data/castle/level/level-dungeon.gltf", "--views", "orbit:3", "--width", "320", "--height",
           "180", "--out", "{OUT}/report", "--quiet"}},
         "data/castle/level/level-dungeon.gltf"},
        {"oa_thor_spawns",
         {{"analyze", kThor, "--views", "spawns", "--width", "160", "--height", "90", "--out", "{OUT}/report",
           "--quiet"}},
         "data/openarena/pak6-patch088.pk3"},
    };
}

std::string replaceAll(std::string s, const std::string &from, const std::string &to) {
    for (size_t p = 0; (p = s.find(from, p)) != std::string::npos; p += to.size()) s.replace(p, from.size(), to);
    return s;
}

// "relative/path sha1" per file under `root`, sorted by path.
std::map<std::string, std::string> hashTree(const fs::path &root) {
    std::map<std::string, std::string> out;
    for (const auto &e : fs::recursive_directory_iterator(root)) {
        if (!e.is_regular_file()) continue;
        const std::string bytes = slurpFile(e.path());
        out[fs::relative(e.path(), root).generic_string()] = OIIO::SHA1::digest(bytes.data(), bytes.size());
    }
    return out;
}

std::map<std::string, std::string> readManifest(const fs::path &p) {
    std::map<std::string, std::string> m;
    std::ifstream f(p);
    std::string path, hash;
    while (f >> path >> hash) m[path] = hash;
    return m;
}

void writeManifest(const fs::path &p, const std::map<std::string, std::string> &m) {
    fs::create_directories(p.parent_path());
    std::ofstream f(p);
    for (const auto &[path, hash] : m) f << path << ' ' << hash << '\n';
}

class Golden : public ::testing::TestWithParam<GoldenCase> {};

TEST_P(Golden, OutputsUnchanged) {
    const GoldenCase &c = GetParam();
    const fs::path src = VISAUDIT_SOURCE_DIR;
    if (c.needs && !fs::exists(src / c.needs))
        GTEST_SKIP() << c.needs << " is absent: run scripts/fetch-data.sh to fetch it";
    ::setenv("VISAUDIT_FIXED_TIMINGS", "1", 1);

    // The runs happen in a folder of their own that links the source folder's examples/ and data/,
    // so every path the program sees, prints or records is relative and the same wherever the
    // checkout and the build folder are.
    const fs::path work = fs::temp_directory_path() / ("visaudit-golden-" + std::to_string(getpid()) + "-" + c.name);
    fs::remove_all(work);
    fs::create_directories(work / "out");
    fs::create_directory_symlink(src / "examples", work / "examples");
    if (fs::exists(src / "data")) fs::create_directory_symlink(src / "data", work / "data");
    ASSERT_EQ(::chdir(work.c_str()), 0);
    int step = 0;
    for (const auto &cmd : c.commands) {
        std::vector<std::string> args;
        for (const std::string &a : cmd) args.push_back(replaceAll(a, "{OUT}", "out"));
        const auto r = runBinary(args, work);
        ASSERT_TRUE(r.code == 0 || r.code == 1) << "step " << step << " exit " << r.code << "\n" << r.err;
        // What the program printed is output too (the --json summary, check's verdict).
        std::ofstream(work / "out" / ("step" + std::to_string(step) + ".stdout")) << r.out;
        std::ofstream(work / "out" / ("step" + std::to_string(step) + ".exit")) << r.code << '\n';
        ++step;
    }
    ASSERT_EQ(::chdir(src.c_str()), 0);
    // Kept for a look when the outputs differ.
    const fs::path actual = fs::path(VISAUDIT_BINARY).parent_path() / "tests" / "golden-actual" / c.name;
    fs::remove_all(actual);
    const std::map<std::string, std::string> got = hashTree(work / "out");
    const fs::path manifest = src / "tests" / "golden" / (std::string(c.name) + ".sha1");
    const char *update = std::getenv("VISAUDIT_UPDATE_GOLDEN");
    if (update && *update && std::string(update) != "0") {
        writeManifest(manifest, got);
        std::printf("wrote %s (%zu files)\n", manifest.c_str(), got.size());
        fs::remove_all(work);
        return;
    }
    ASSERT_TRUE(fs::exists(manifest)) << manifest << " is missing: regenerate with VISAUDIT_UPDATE_GOLDEN=1";
    const std::map<std::string, std::string> want = readManifest(manifest);
    std::vector<std::string> differ, missing, extra;
    for (const auto &[path, hash] : want) {
        auto it = got.find(path);
        if (it == got.end())
            missing.push_back(path);
        else if (it->second != hash)
            differ.push_back(path);
    }
    for (const auto &[path, hash] : got)
        if (!want.count(path)) extra.push_back(path);
    auto list = [](const std::vector<std::string> &v) {
        std::string s;
        for (size_t i = 0; i < v.size() && i < 40; ++i) s += "\n  " + v[i];
        if (v.size() > 40) s += "\n  ... and " + std::to_string(v.size() - 40) + " more";
        return s;
    };
    EXPECT_TRUE(differ.empty()) << differ.size() << " file(s) differ from " << manifest << ":" << list(differ)
                                << "\n(the run is kept in " << actual
                                << "; if the change is meant, regenerate with VISAUDIT_UPDATE_GOLDEN=1)";
    EXPECT_TRUE(missing.empty()) << missing.size() << " file(s) no longer written:" << list(missing);
    EXPECT_TRUE(extra.empty()) << extra.size() << " new file(s) not in the manifest:" << list(extra);
    if (!differ.empty() || !missing.empty() || !extra.empty()) {
        fs::create_directories(actual);
        fs::copy(work / "out", actual / "out", fs::copy_options::recursive);
        writeManifest(actual / (std::string(c.name) + ".sha1"), got);
    }
    fs::remove_all(work);
}

INSTANTIATE_TEST_SUITE_P(Outputs, Golden, ::testing::ValuesIn(goldenCases()),
                         [](const ::testing::TestParamInfo<GoldenCase> &i) { return std::string(i.param.name); });

}  // namespace
