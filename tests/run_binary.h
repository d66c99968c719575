// Runs the real program (VISAUDIT_BINARY) as a child process, for the tests that need what only a
// process has: its exit code or signal, its peak memory (wait4's ru_maxrss, of this child alone),
// signals sent to it while it runs.
#pragma once

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace va::testing_util {

struct ChildResult {
    int code = -1;        // exit code; -1 when a signal ended it
    int signal = 0;       // the signal that ended it, or 0
    std::string out, err; // what it printed
    long maxRssKiB = 0;   // its peak resident memory
    double seconds = 0;   // wall time from spawn to exit
};

struct Child {
    pid_t pid = -1;
    std::filesystem::path outFile, errFile;
    std::chrono::steady_clock::time_point start;
};

// Starts VISAUDIT_BINARY with `args` (no shell), stdin /dev/null, stdout and stderr into files in `dir`.
inline Child spawnBinary(const std::vector<std::string> &args, const std::filesystem::path &dir) {
    Child c;
    c.outFile = dir / "child.stdout";
    c.errFile = dir / "child.stderr";
    // A fresh pair of files: whoever polls them sees this child's output, never an earlier one's.
    std::filesystem::remove(c.outFile);
    std::filesystem::remove(c.errFile);
    c.start = std::chrono::steady_clock::now();
    std::vector<std::string> argv = {VISAUDIT_BINARY};
    argv.insert(argv.end(), args.begin(), args.end());
    c.pid = ::fork();
    if (c.pid == 0) {
        const int in = ::open("/dev/null", O_RDONLY);
        const int out = ::open(c.outFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        const int err = ::open(c.errFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (in < 0 || out < 0 || err < 0) ::_exit(127);
        ::dup2(in, 0);
        ::dup2(out, 1);
        ::dup2(err, 2);
        std::vector<char *> p;
        for (auto &a : argv) p.push_back(a.data());
        p.push_back(nullptr);
        ::execv(p[0], p.data());
        ::_exit(127);
    }
    return c;
}

inline std::string slurpFile(const std::filesystem::path &p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

inline ChildResult waitChild(const Child &c) {
    ChildResult r;
    int status = 0;
    struct rusage ru = {};
    while (::wait4(c.pid, &status, 0, &ru) < 0 && errno == EINTR) {
    }
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - c.start).count();
    if (WIFEXITED(status)) r.code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
    r.maxRssKiB = ru.ru_maxrss;
    r.out = slurpFile(c.outFile);
    r.err = slurpFile(c.errFile);
    return r;
}

inline ChildResult runBinary(const std::vector<std::string> &args, const std::filesystem::path &dir) {
    return waitChild(spawnBinary(args, dir));
}

}  // namespace va::testing_util
