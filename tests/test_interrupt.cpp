// Nothing lost (docs/limits.md): SIGINT and SIGTERM during analyze stop it cleanly -- exit 128 +
// signal with one line, no staging folder left, the previous report byte for byte -- and a failed
// write (disk full, a read-only file system, a path through a file) names the path and the
// system's reason, exits 2 and keeps the previous report. These run as root too: they use
// /dev/full and small tmpfs mounts (skipped where mounting is not permitted), not permissions.
// Suites Interrupt*, WriteFailure*.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/mount.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "tests/run_binary.h"
#include "tests/temp_dir_test.h"

namespace va {
namespace {

namespace fs = std::filesystem;
using namespace testing_util;

// Every file under `dir` (relative path -> bytes).
std::map<std::string, std::string> snapshot(const fs::path &dir) {
    std::map<std::string, std::string> files;
    for (const auto &e : fs::recursive_directory_iterator(dir))
        if (e.is_regular_file()) files[fs::relative(e.path(), dir).string()] = slurpFile(e.path());
    return files;
}

// Staging ("NAME.tmp-PID-K") and replaced ("NAME.old-PID-K") folders left next to the output.
std::vector<std::string> leftovers(const fs::path &parent) {
    std::vector<std::string> names;
    for (const auto &e : fs::directory_iterator(parent)) {
        const std::string n = e.path().filename().string();
        if (n.find(".tmp-") != std::string::npos || n.find(".old-") != std::string::npos) names.push_back(n);
    }
    return names;
}

std::string lastLine(const std::string &text) {
    std::string t = text;
    while (!t.empty() && t.back() == '\n') t.pop_back();
    const size_t nl = t.rfind('\n');
    return nl == std::string::npos ? t : t.substr(nl + 1);
}

// True once `pid` has a handler for `sig` (bit sig - 1 of SigCgt in /proc/PID/status).
bool catches(pid_t pid, int sig) {
    std::ifstream f("/proc/" + std::to_string(pid) + "/status");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind("SigCgt:", 0) == 0) return (std::stoull(line.substr(7), nullptr, 16) >> (sig - 1)) & 1;
    return false;
}

class NothingLost : public testing_util::TempDirTest {
  protected:
    NothingLost() : TempDirTest("lost") {}

    void SetUp() override {
        TempDirTest::SetUp();
        fs::create_directories(dir_ / "logs");
    }
    void TearDown() override {
        if (mounted_) ::umount2(mount_.c_str(), MNT_DETACH);
        TempDirTest::TearDown();
    }
    // A tmpfs of `bytes` at dir_/mnt; false (and the test skips) where mounting is not permitted.
    bool mountTmpfs(uint64_t bytes) {
        mount_ = dir_ / "mnt";
        fs::create_directories(mount_);
        const std::string opt = "size=" + std::to_string(bytes);
        if (::mount("tmpfs", mount_.c_str(), "tmpfs", 0, opt.c_str()) != 0) {
            skipWhy_ = std::string("cannot mount a tmpfs here (") + std::strerror(errno) +
                       "); needs CAP_SYS_ADMIN, as root in a container with mount rights";
            return false;
        }
        mounted_ = true;
        return true;
    }
    // A small report (the demo's first view at 64 x 36) in `out`.
    void priorReport(const fs::path &out) {
        const auto r = runBinary({"analyze", "--quiet", "--views", "orbit:1", "--width", "64", "--height", "36", "--out",
                                  out.string()},
                                 dir_ / "logs");
        ASSERT_EQ(r.code, 0) << r.err;
    }
    fs::path mount_;
    bool mounted_ = false;
    std::string skipWhy_;
};

// The run to interrupt: the demo from 12 orbit views at 1280 x 720 on one thread, several seconds.
const std::vector<std::string> kLongRun = {"analyze", "--views", "orbit:12", "--width", "1280", "--height", "720",
                                           "--threads", "1"};

enum class When { handlersInstalled, firstViewDone, halfTheViewsDone };

// Starts the long run into `out`, waits for the point `when`, sends `sig`, waits for the exit.
ChildResult interruptAt(const fs::path &out, const fs::path &logs, When when, int sig, double *latency) {
    std::vector<std::string> args = kLongRun;
    args.insert(args.end(), {"--out", out.string()});
    const Child c = spawnBinary(args, logs);
    // Poll the child's state: its handlers (/proc), its progress lines ("[k/12] NAME ms" on stderr).
    const std::string mark = when == When::firstViewDone ? "[1/12]" : "[6/12]";
    for (int i = 0; i < 60000; ++i) {
        if (catches(c.pid, sig) &&
            (when == When::handlersInstalled || slurpFile(c.errFile).find(mark) != std::string::npos))
            break;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    const auto sent = std::chrono::steady_clock::now();
    ::kill(c.pid, sig);
    ChildResult r = waitChild(c);
    *latency = std::chrono::duration<double>(std::chrono::steady_clock::now() - sent).count();
    return r;
}

// SIGINT and SIGTERM at three points: while loading (before the staging folder exists), after the
// first view's images are in the staging folder, half-way. Every time: 128 + signal, the one
// line, the previous report byte for byte, nothing left next to it.
TEST_F(NothingLost, InterruptedRunKeepsThePreviousReport) {
    const fs::path out = dir_ / "report";
    priorReport(out);
    const auto before = snapshot(out);
    ASSERT_FALSE(before.empty());
    for (When when : {When::handlersInstalled, When::firstViewDone, When::halfTheViewsDone})
        for (int sig : {SIGINT, SIGTERM}) {
            double latency = 0;
            const ChildResult r = interruptAt(out, dir_ / "logs", when, sig, &latency);
            const std::string name = sig == SIGINT ? "SIGINT" : "SIGTERM";
            SCOPED_TRACE(name + " at point " + std::to_string(int(when)));
            EXPECT_EQ(r.signal, 0);
            EXPECT_EQ(r.code, 128 + sig) << r.err;
            EXPECT_EQ(lastLine(r.err),
                      "visaudit: interrupted by " + name + "; nothing was written; '" + out.string() + "' is as it was");
            EXPECT_TRUE(snapshot(out) == before);  // byte for byte (not printed: images)
            EXPECT_EQ(leftovers(dir_), std::vector<std::string>{});
            // The flag is polled between stages: one stage of one 1280 x 720 view at most.
            EXPECT_LT(latency, 5.0);
            std::printf("  %s at point %d: stopped %.3f s after the signal\n", name.c_str(), int(when), latency);
        }
}

// Where nothing existed, nothing is left: no folder, no staging folder.
TEST_F(NothingLost, InterruptedFirstRunLeavesNoFolder) {
    const fs::path out = dir_ / "fresh";
    double latency = 0;
    const ChildResult r = interruptAt(out, dir_ / "logs", When::firstViewDone, SIGINT, &latency);
    EXPECT_EQ(r.code, 130) << r.err;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_EQ(leftovers(dir_), std::vector<std::string>{});
}

// A file output on a full device: the path and the system's reason, exit 2. The report folder,
// committed before the JUnit file, is complete.
TEST_F(NothingLost, WriteFailureDevFull) {
    const auto r = runBinary({"check", "--quiet", "--width", "64", "--height", "36", "--budget",
                              std::string(VISAUDIT_EXAMPLES) + "/demo.budget.json", "--junit", "/dev/full", "--out",
                              (dir_ / "report").string()},
                             dir_ / "logs");
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(lastLine(r.err), "visaudit: error: cannot write '/dev/full': write: No space left on device");
    EXPECT_TRUE(fs::is_character_file("/dev/full"));  // written in place, never replaced by a file
    EXPECT_TRUE(fs::exists(dir_ / "report" / "report.json"));
}

// A disk that fills while the new report is being written: the error names the file being
// written, the staging folder is removed and the previous report is untouched.
TEST_F(NothingLost, WriteFailureDiskFull) {
    // 384 KiB: the small report (about 150 KiB) fits, the new one (about 470 KiB) does not.
    if (!mountTmpfs(384 << 10)) GTEST_SKIP() << skipWhy_;
    const fs::path out = mount_ / "report";
    priorReport(out);
    const auto before = snapshot(out);
    const auto r = runBinary({"analyze", "--quiet", "--views", "orbit:2", "--width", "1280", "--height", "720", "--out",
                              out.string()},
                             dir_ / "logs");
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err.rfind("visaudit: error: cannot write ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(out.string() + ".tmp-"), std::string::npos) << r.err;  // the file's path
    EXPECT_NE(r.err.find("No space left on device"), std::string::npos) << r.err;
    EXPECT_TRUE(snapshot(out) == before);  // byte for byte (not printed: images)
    EXPECT_EQ(leftovers(mount_), std::vector<std::string>{});
}

// A read-only file system stops root too (unlike folder permissions: OutputDir.ReadOnlyParent).
TEST_F(NothingLost, WriteFailureReadOnlyFileSystem) {
    if (!mountTmpfs(8 << 20)) GTEST_SKIP() << skipWhy_;
    const fs::path out = mount_ / "report";
    priorReport(out);
    const auto before = snapshot(out);
    ASSERT_EQ(::mount("tmpfs", mount_.c_str(), "tmpfs", MS_REMOUNT | MS_RDONLY, nullptr), 0) << std::strerror(errno);
    const auto r = runBinary({"analyze", "--quiet", "--views", "orbit:1", "--width", "64", "--height", "36", "--out",
                              out.string()},
                             dir_ / "logs");
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err.rfind("visaudit: error: cannot create staging folder '" + out.string() + ".tmp-", 0), 0u) << r.err;
    EXPECT_NE(r.err.find("': Read-only file system\n"), std::string::npos) << r.err;
    EXPECT_TRUE(snapshot(out) == before);  // byte for byte (not printed: images)
    EXPECT_EQ(leftovers(mount_), std::vector<std::string>{});
}

// --out through a regular file: the folder that cannot be made, and why.
TEST_F(NothingLost, WriteFailurePathThroughAFile) {
    std::ofstream(dir_ / "file") << "x";
    const auto r = runBinary({"analyze", "--quiet", "--views", "orbit:1", "--width", "64", "--height", "36", "--out",
                              (dir_ / "file" / "sub" / "report").string()},
                             dir_ / "logs");
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: cannot use output folder '" + (dir_ / "file" / "sub" / "report").string() +
                         "': Not a directory\n");
    EXPECT_EQ(slurpFile(dir_ / "file"), "x");
}

}  // namespace
}  // namespace va
