// writeFileAtomic and OutputDir: a report folder is replaced as a whole or not at all, and a
// folder that is not a visaudit report is never touched.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "reports/report.h"

namespace va {
namespace {

namespace fs = std::filesystem;

struct TempRoot {
    std::string path;
    TempRoot() {
        std::string t = (fs::temp_directory_path() / "visaudit-output-XXXXXX").string();
        path = ::mkdtemp(t.data()) ? t : "";
    }
    ~TempRoot() {
        std::error_code ec;
        if (path.empty()) return;
        fs::permissions(path, fs::perms::owner_all, fs::perm_options::add, ec);
        fs::remove_all(path, ec);
    }
};

std::string readFile(const std::string &p) {
    std::ifstream f(p);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}
void writeFile(const std::string &p, const std::string &s) { std::ofstream(p) << s; }

// Names in a folder, sorted.
std::vector<std::string> list(const std::string &dir) {
    std::vector<std::string> v;
    for (const auto &e : fs::directory_iterator(dir)) v.push_back(e.path().filename().string());
    std::sort(v.begin(), v.end());
    return v;
}

bool contains(const std::string &s, const std::string &part) { return s.find(part) != std::string::npos; }

TEST(OutputFile, WritesAtomically) {
    TempRoot root;
    ASSERT_FALSE(root.path.empty());
    const std::string p = root.path + "/report.json";
    std::string err;
    ASSERT_TRUE(writeFileAtomic(p, "{\"a\":1}\n", &err)) << err;
    EXPECT_EQ(readFile(p), "{\"a\":1}\n");
    ASSERT_TRUE(writeFileAtomic(p, "second", &err)) << err;  // replaces
    EXPECT_EQ(readFile(p), "second");
    ASSERT_TRUE(writeFileAtomic(root.path + "/empty.txt", "", &err)) << err;
    EXPECT_EQ(fs::file_size(root.path + "/empty.txt"), 0u);
    EXPECT_EQ(list(root.path), (std::vector<std::string>{"empty.txt", "report.json"}));  // no temporaries left
}

TEST(OutputFile, ErrorsNameThePath) {
    TempRoot root;
    std::string err;
    const std::string p = root.path + "/missing/report.json";
    EXPECT_FALSE(writeFileAtomic(p, "x", &err));
    EXPECT_TRUE(contains(err, "cannot write '" + p + "'")) << err;
    EXPECT_TRUE(contains(err, "No such file or directory")) << err;

    // A folder where the file should go: the rename fails, the temporary is removed.
    fs::create_directory(root.path + "/adir");
    writeFile(root.path + "/adir/keep", "k");
    EXPECT_FALSE(writeFileAtomic(root.path + "/adir", "x", &err));
    EXPECT_TRUE(contains(err, "cannot write '" + root.path + "/adir': rename from")) << err;
    EXPECT_EQ(list(root.path), std::vector<std::string>{"adir"});
    EXPECT_EQ(readFile(root.path + "/adir/keep"), "k");
}

TEST(OutputDir, CreatesNewFolder) {
    TempRoot root;
    const std::string target = root.path + "/nested/out";
    std::string err;
    {
        OutputDir out;
        ASSERT_TRUE(out.open(target + "/", &err)) << err;  // trailing slash names the same folder
        EXPECT_EQ(out.target(), target);
        EXPECT_EQ(fs::path(out.staging()).parent_path(), fs::path(root.path + "/nested"));  // same file system
        EXPECT_TRUE(contains(out.staging(), "out.tmp-" + std::to_string(::getpid()) + "-"));
        EXPECT_FALSE(fs::exists(target));  // nothing visible before commit
        ASSERT_TRUE(writeFileAtomic(out.staging() + "/report.json", "new", &err)) << err;
        ASSERT_TRUE(out.commit(&err)) << err;
    }
    EXPECT_EQ(readFile(target + "/report.json"), "new");
    EXPECT_EQ(list(root.path + "/nested"), std::vector<std::string>{"out"});  // no staging, no .old
}

TEST(OutputDir, CommitReplacesOldReport) {
    TempRoot root;
    const std::string target = root.path + "/out";
    fs::create_directory(target);
    writeFile(target + "/report.json", "old");
    writeFile(target + "/stale.depth.png", "old image");
    std::string err;
    {
        OutputDir out;
        ASSERT_TRUE(out.open(target, &err)) << err;
        EXPECT_EQ(readFile(target + "/report.json"), "old");  // untouched until commit
        writeFile(out.staging() + "/report.json", "new");
        ASSERT_TRUE(out.commit(&err)) << err;
        EXPECT_TRUE(err.empty()) << err;
    }
    EXPECT_EQ(list(target), std::vector<std::string>{"report.json"});  // the old folder is gone as a whole
    EXPECT_EQ(readFile(target + "/report.json"), "new");
    EXPECT_EQ(list(root.path), std::vector<std::string>{"out"});
}

TEST(OutputDir, AcceptsEmptyFolder) {
    TempRoot root;
    const std::string target = root.path + "/empty";
    fs::create_directory(target);
    OutputDir out;
    std::string err;
    ASSERT_TRUE(out.open(target, &err)) << err;
    writeFile(out.staging() + "/report.json", "r");
    ASSERT_TRUE(out.commit(&err)) << err;
    EXPECT_EQ(readFile(target + "/report.json"), "r");
}

TEST(OutputDir, RefusesFolderThatIsNotAReport) {
    TempRoot root;
    const std::string target = root.path + "/thesis";
    fs::create_directory(target);
    writeFile(target + "/chapter1.tex", "precious");
    std::string err;
    {
        OutputDir out;
        EXPECT_FALSE(out.open(target, &err));
        EXPECT_EQ(err, "refusing to replace '" + target +
                           "': it is not empty and holds no report.json, so it is not a visaudit report folder; "
                           "choose another --out folder (or an empty one)");
        EXPECT_TRUE(out.staging().empty());
    }
    EXPECT_EQ(list(target), std::vector<std::string>{"chapter1.tex"});
    EXPECT_EQ(readFile(target + "/chapter1.tex"), "precious");
    EXPECT_EQ(list(root.path), std::vector<std::string>{"thesis"});  // no staging folder was made

    // report.json must be a file: a folder of that name does not make a report folder.
    fs::create_directory(target + "/report.json");
    OutputDir again;
    EXPECT_FALSE(again.open(target, &err));
}

TEST(OutputDir, RefusesAFileAsTarget) {
    TempRoot root;
    const std::string target = root.path + "/out";
    writeFile(target, "a file");
    OutputDir out;
    std::string err;
    EXPECT_FALSE(out.open(target, &err));
    EXPECT_EQ(err, "refusing to use '" + target + "' as output folder: it exists and is not a folder; choose another --out folder");
    EXPECT_EQ(readFile(target), "a file");
}

// A file where a parent folder is expected fails deterministically, root or not.
TEST(OutputDir, ParentIsAFile) {
    TempRoot root;
    writeFile(root.path + "/plain", "x");
    const std::string target = root.path + "/plain/out";
    OutputDir out;
    std::string err;
    EXPECT_FALSE(out.open(target, &err));
    EXPECT_TRUE(contains(err, root.path + "/plain")) << err;
    EXPECT_TRUE(contains(err, "Not a directory")) << err;
}

TEST(OutputDir, ReadOnlyParent) {
    if (::geteuid() == 0) GTEST_SKIP() << "running as root, which ignores folder permissions (ParentIsAFile covers the error path)";
    TempRoot root;
    const std::string parent = root.path + "/ro";
    fs::create_directory(parent);
    fs::permissions(parent, fs::perms::owner_read | fs::perms::owner_exec);
    OutputDir out;
    std::string err;
    EXPECT_FALSE(out.open(parent + "/out", &err));
    EXPECT_TRUE(contains(err, "cannot create staging folder '" + parent + "/out.tmp-")) << err;
    EXPECT_TRUE(contains(err, "Permission denied")) << err;
    fs::permissions(parent, fs::perms::owner_all);
}

TEST(OutputDir, AbandonedLeavesOldReportAndNoStaging) {
    TempRoot root;
    const std::string target = root.path + "/out";
    fs::create_directory(target);
    writeFile(target + "/report.json", "old");
    std::string staging, err;
    {
        OutputDir out;
        ASSERT_TRUE(out.open(target, &err)) << err;
        staging = out.staging();
        writeFile(staging + "/report.json", "half-written");
        fs::create_directory(staging + "/sub");
        writeFile(staging + "/sub/x", "x");
        EXPECT_TRUE(fs::exists(staging));
    }  // destroyed without commit: a failed run
    EXPECT_FALSE(fs::exists(staging));
    EXPECT_EQ(readFile(target + "/report.json"), "old");
    EXPECT_EQ(list(root.path), std::vector<std::string>{"out"});
}

TEST(OutputDir, FailedCommitKeepsOldReport) {
    TempRoot root;
    const std::string target = root.path + "/out";
    fs::create_directory(target);
    writeFile(target + "/report.json", "old");
    OutputDir out;
    std::string err;
    ASSERT_TRUE(out.open(target, &err)) << err;
    // Make the commit fail: the staging folder disappears before it. Its files are flushed to
    // disk before anything is swapped, so that fails first and the old report is never touched.
    const std::string staging = out.staging();
    fs::remove_all(staging);
    EXPECT_FALSE(out.commit(&err));
    EXPECT_EQ(err, "cannot flush staging folder '" + staging + "' to disk: No such file or directory");
    EXPECT_EQ(readFile(target + "/report.json"), "old");
    EXPECT_EQ(list(root.path), std::vector<std::string>{"out"});
}

// A file written into an open staging folder is written plainly, in place (a hard link to it
// sees the new contents), one written anywhere else atomically (a new file renamed over it: the
// link keeps the old contents); after the commit the folder is an ordinary folder again.
TEST(OutputDir, StagingFilesAreWrittenInPlace) {
    TempRoot root;
    OutputDir out;
    std::string err;
    ASSERT_TRUE(out.open(root.path + "/out", &err)) << err;
    writeFile(out.staging() + "/a.txt", "old");
    fs::create_hard_link(out.staging() + "/a.txt", root.path + "/link-a");
    ASSERT_TRUE(writeFileAtomic(out.staging() + "/a.txt", "staged", &err)) << err;
    EXPECT_EQ(readFile(root.path + "/link-a"), "staged");
    ASSERT_TRUE(out.commit(&err)) << err;
    EXPECT_EQ(readFile(root.path + "/out/a.txt"), "staged");
    fs::create_hard_link(root.path + "/out/a.txt", root.path + "/link-b");
    ASSERT_TRUE(writeFileAtomic(root.path + "/out/a.txt", "direct", &err)) << err;
    EXPECT_EQ(readFile(root.path + "/out/a.txt"), "direct");
    EXPECT_EQ(readFile(root.path + "/link-b"), "staged");
    EXPECT_EQ(list(root.path + "/out"), std::vector<std::string>{"a.txt"});
}

TEST(OutputDir, CommitRechecksTheTarget) {
    TempRoot root;
    const std::string target = root.path + "/out";
    OutputDir out;
    std::string err;
    ASSERT_TRUE(out.open(target, &err)) << err;
    // Someone puts unrelated data at the target while the analysis runs.
    fs::create_directory(target);
    writeFile(target + "/notes.txt", "mine");
    EXPECT_FALSE(out.commit(&err));
    EXPECT_TRUE(contains(err, "refusing to replace '" + target + "'")) << err;
    EXPECT_EQ(readFile(target + "/notes.txt"), "mine");
}

TEST(OutputDir, CommitWithoutOpenFails) {
    OutputDir out;
    std::string err;
    EXPECT_FALSE(out.commit(&err));
    EXPECT_EQ(err, "output folder was not opened (call open() first)");
}

}  // namespace
}  // namespace va
