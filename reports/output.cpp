// Atomic outputs: single files (temporary name + rename) and whole report folders (staging folder
// + swap). rename(2) within one file system is atomic, so every temporary lives next to its target.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <mutex>
#include <set>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>

#include "reports/report.h"

#include "common/json_util.h"

namespace va {

namespace fs = std::filesystem;

namespace {

std::atomic<unsigned> gCounter{0};

// The staging folders of the OutputDirs open in this process (writeFileAtomic writes plainly into
// them; OutputDir::commit makes them durable as a whole).
std::mutex gStagingMutex;
std::set<std::string> gStaging;

bool inStagingFolder(const std::string &path) {
    const std::string dir = fs::path(path).parent_path().string();
    std::lock_guard<std::mutex> lock(gStagingMutex);
    return gStaging.count(dir) > 0;
}
void setStaging(const std::string &dir, bool open) {
    std::lock_guard<std::mutex> lock(gStagingMutex);
    if (open) gStaging.insert(dir);
    else gStaging.erase(dir);
}

std::string errnoText(int e) { return std::strerror(e); }

// "<path>" without trailing slashes ("out/" and "out" name the same folder; the staging folder is
// "<path>.tmp-..." next to it, not inside it). "/" stays "/".
std::string stripTrailingSlashes(std::string p) {
    while (p.size() > 1 && p.back() == '/') p.pop_back();
    return p;
}

bool isDirectory(const std::string &p) {
    struct stat st;
    return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

// Whether an existing folder may be replaced: empty, or a visaudit report folder (holds a regular
// file report.json, or pvs-audit.json: a pvs-audit folder). Anything else is someone's data and is
// never touched.
bool replaceable(const std::string &dir, std::string *why) {
    std::error_code ec;
    fs::directory_iterator it(dir, ec);
    if (ec) {
        *why = "cannot list '" + dir + "': " + ec.message();
        return false;
    }
    if (it == fs::directory_iterator()) return true;
    if (fs::is_regular_file(fs::path(dir) / "report.json", ec)) return true;
    if (fs::is_regular_file(fs::path(dir) / "pvs-audit.json", ec)) return true;
    if (fs::is_regular_file(fs::path(dir) / "diff.json", ec)) return true;  // visaudit diff's folder
    // An assignment kit, its answers, a student's grade, a class's grades.
    for (const char *marker : {"assignment.json", "answers.json", "grade.json", "grades.csv"})
        if (fs::is_regular_file(fs::path(dir) / marker, ec)) return true;
    *why = "refusing to replace '" + dir +
           "': it is not empty and holds no report.json, so it is not a visaudit report folder; "
           "choose another --out folder (or an empty one)";
    return false;
}

}  // namespace

namespace {
// Writes all of `contents` to fd (write(2) may write fewer bytes than asked); errno on failure.
bool writeAll(int fd, const std::string &contents) {
    size_t done = 0;
    while (done < contents.size()) {
        const ssize_t w = ::write(fd, contents.data() + done, contents.size() - done);
        if (w < 0) {
            if (errno == EINTR) continue;
            return false;
        }
        done += size_t(w);
    }
    return true;
}
}  // namespace

bool writeFileAtomic(const std::string &path, const std::string &contents, std::string *err) {
    // A target that exists and is not a regular file (/dev/stdout, a FIFO, /dev/full) is written in
    // place: renaming a temporary over it would replace the device node itself (as root, /dev is
    // writable), and there is no half-written file to protect.
    struct stat st;
    if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode)) {
        const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
        if (fd < 0) {
            if (err) *err = "cannot write '" + path + "': open: " + errnoText(errno);
            return false;
        }
        if (!writeAll(fd, contents)) {
            const int e = errno;
            ::close(fd);
            if (err) *err = "cannot write '" + path + "': write: " + errnoText(e);
            return false;
        }
        if (::close(fd) != 0) {
            if (err) *err = "cannot write '" + path + "': close: " + errnoText(errno);
            return false;
        }
        return true;
    }
    if (inStagingFolder(path)) {
        // Plainly (see report.h): a failed write leaves a partial file in a folder that is never
        // committed.
        const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
        if (fd < 0) {
            if (err) *err = "cannot write '" + path + "': create: " + errnoText(errno);
            return false;
        }
        if (!writeAll(fd, contents)) {
            const int e = errno;
            ::close(fd);
            if (err) *err = "cannot write '" + path + "': write: " + errnoText(e);
            return false;
        }
#if defined(__linux__)
        // Start the file's writeback now (without waiting for it), so that the commit's syncfs
        // finds the run's images mostly on the disk already instead of waiting for all of them.
        ::sync_file_range(fd, 0, 0, SYNC_FILE_RANGE_WRITE);
#endif
        if (::close(fd) != 0) {
            if (err) *err = "cannot write '" + path + "': close: " + errnoText(errno);
            return false;
        }
        return true;
    }
    const std::string tmp = path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(gCounter.fetch_add(1));
    auto fail = [&](const std::string &what, int e, bool removeTmp) {
        if (removeTmp) ::unlink(tmp.c_str());
        if (err) *err = "cannot write '" + path + "': " + what + ": " + errnoText(e);
        return false;
    };
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) return fail("create '" + tmp + "'", errno, false);
    // Write all bytes, then flush them to the disk before the rename makes the file visible under
    // its real name.
    if (!writeAll(fd, contents)) {
        const int e = errno;
        ::close(fd);
        return fail("write", e, true);
    }
    if (::fsync(fd) != 0) {
        const int e = errno;
        ::close(fd);
        return fail("fsync", e, true);
    }
    if (::close(fd) != 0) return fail("close", errno, true);
    if (::rename(tmp.c_str(), path.c_str()) != 0) return fail("rename from '" + tmp + "'", errno, true);
    return true;
}

bool OutputDir::open(const std::string &target, std::string *err) {
    // A second open() abandons the first staging folder.
    if (!committed_ && !staging_.empty()) {
        setStaging(staging_, false);
        std::error_code ec;
        fs::remove_all(staging_, ec);
    }
    committed_ = false;
    staging_.clear();
    target_ = stripTrailingSlashes(target);
    if (target_.empty()) {
        if (err) *err = "empty output folder name; pass --out FOLDER";
        return false;
    }

    // The target may be absent, an empty folder or a report folder; anything else is refused now,
    // before any work is done.
    struct stat st;
    if (::lstat(target_.c_str(), &st) == 0) {
        if (!isDirectory(target_)) {
            if (err) *err = "refusing to use '" + target_ + "' as output folder: it exists and is not a folder; "
                            "choose another --out folder";
            return false;
        }
        std::string why;
        if (!replaceable(target_, &why)) {
            if (err) *err = why;
            return false;
        }
    } else if (errno != ENOENT) {
        if (err) *err = "cannot use output folder '" + target_ + "': " + errnoText(errno);
        return false;
    }

    // The parent must exist for the staging folder (same file system as the target); missing parent
    // folders are created, as `mkdir -p` would.
    const fs::path parent = fs::path(target_).parent_path();
    if (!parent.empty()) {
        std::error_code ec;
        fs::create_directories(parent, ec);
        if (ec) {
            if (err) *err = "cannot create folder '" + parent.string() + "' for output '" + target_ + "': " + ec.message();
            return false;
        }
    }
    const std::string staging =
        target_ + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(gCounter.fetch_add(1));
    if (::mkdir(staging.c_str(), 0777) != 0) {
        if (err) *err = "cannot create staging folder '" + staging + "': " + errnoText(errno);
        return false;
    }
    staging_ = staging;
    setStaging(staging_, true);
    return true;
}

bool OutputDir::commit(std::string *err) {
    if (staging_.empty() || committed_) {
        if (err) *err = committed_ ? "output folder '" + target_ + "' was already committed"
                                   : "output folder was not opened (call open() first)";
        return false;
    }
    // Every file in the staging folder reaches the disk before the folder becomes the report: one
    // syncfs for the file system (a journal commit), then the folder's own entries.
    {
        const int fd = ::open(staging_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
        if (fd < 0 || ::syncfs(fd) != 0 || ::fsync(fd) != 0) {
            const int e = errno;
            if (fd >= 0) ::close(fd);
            if (err) *err = "cannot flush staging folder '" + staging_ + "' to disk: " + errnoText(e);
            return false;
        }
        ::close(fd);
    }
    setStaging(staging_, false);
    // Check the target again: it may have changed since open().
    std::string old;
    struct stat st;
    if (::lstat(target_.c_str(), &st) == 0) {
        std::string why;
        if (!isDirectory(target_)) {
            if (err) *err = "refusing to replace '" + target_ + "': it is no longer a folder";
            return false;
        }
        if (!replaceable(target_, &why)) {
            if (err) *err = why;
            return false;
        }
        // Move the old report aside (atomic), so that the target name is free for the new one.
        // "<target>.old-<pid>-<counter>": the counter keeps two commits in one process apart.
        old = target_ + ".old-" + std::to_string(::getpid()) + "-" + std::to_string(gCounter.fetch_add(1));
        if (::rename(target_.c_str(), old.c_str()) != 0) {
            if (err) *err = "cannot move old report '" + target_ + "' to '" + old + "': " + errnoText(errno);
            return false;
        }
    } else if (errno != ENOENT) {
        if (err) *err = "cannot use output folder '" + target_ + "': " + errnoText(errno);
        return false;
    }

    // Swap the new report in; on failure put the old one back so nothing is lost.
    if (::rename(staging_.c_str(), target_.c_str()) != 0) {
        const int e = errno;
        std::string msg = "cannot move staging folder '" + staging_ + "' to '" + target_ + "': " + errnoText(e);
        if (!old.empty() && ::rename(old.c_str(), target_.c_str()) != 0)
            msg += "; the previous report is kept at '" + old + "' (" + errnoText(errno) + ")";
        if (err) *err = msg;
        return false;
    }
    committed_ = true;

    // Remove the old report. The swap has already succeeded: a failure here leaves a stale folder,
    // reported as a warning, not an error.
    if (!old.empty()) {
        std::error_code ec;
        fs::remove_all(old, ec);
        if (ec && err) *err = "warning: could not remove the previous report at '" + old + "': " + ec.message();
    }
    return true;
}

OutputDir::~OutputDir() {
    if (!staging_.empty()) setStaging(staging_, false);
    if (!committed_ && !staging_.empty()) {
        std::error_code ec;
        fs::remove_all(staging_, ec);
    }
}

JsonRead readJsonDocument(const std::string &path, nlohmann::ordered_json *out, std::string *detail,
                          uint64_t maxDepth) {
    std::ifstream f(path, std::ios::binary);
    if (!f) return JsonRead::unreadable;
    std::stringstream ss;
    ss << f.rdbuf();
    if (!f && !f.eof()) return JsonRead::unreadable;
    const std::string text = std::move(ss).str();
    std::string deep;
    if (!json::checkDepth(text, path, maxDepth, &deep)) {
        if (detail) *detail = deep;
        return JsonRead::tooDeep;
    }
    try {
        *out = nlohmann::ordered_json::parse(text);
    } catch (const std::exception &e) {
        if (detail) *detail = e.what();
        return JsonRead::invalid;
    }
    return JsonRead::ok;
}

}  // namespace va
