// Shared by the fuzz targets (fuzz/README.md). Loaders that only read paths (OpenMesh, tinygltf,
// libzip, the JSON readers) get the input as a file in a per-process scratch folder on tmpfs:
// writing it costs microseconds next to the parse, and the loader under test is the real one.
//
// Every target checks the loaders' contract (STYLE 9, 10): a loader returns true, or false with a
// message naming the file; it never throws, crashes or returns false silently. A broken contract
// aborts, so libFuzzer records the input.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace va::fuzz {

// /dev/shm/visaudit-fuzz-PID (the temp folder where /dev/shm does not exist), removed at exit.
// The path is never destroyed: the exit handler runs after static destructors may have run.
inline const std::string &scratchDir() {
    static const std::string *const dir = [] {
        namespace fs = std::filesystem;
        const fs::path base = fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
        const fs::path d = base / ("visaudit-fuzz-" + std::to_string(getpid()));
        fs::create_directories(d);
        std::atexit([] {
            std::error_code ec;
            std::filesystem::remove_all(scratchDir(), ec);
        });
        return new std::string(d.string());
    }();
    return *dir;
}

// Writes the input to scratchDir()/name; returns its path.
inline std::string writeInput(const std::string &name, const uint8_t *data, size_t size) {
    const std::string path = scratchDir() + "/" + name;
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char *>(data), std::streamsize(size));
    if (!f) {
        std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
        std::abort();
    }
    return path;
}

// Copies a file of the source tree (seed meshes a scene refers to, a glTF's .bin) next to the input.
inline void provide(const std::string &sourceRelative, const std::string &name) {
    namespace fs = std::filesystem;
    const fs::path to = fs::path(scratchDir()) / name;
    fs::create_directories(to.parent_path());
    std::error_code ec;
    fs::copy_file(fs::path(VISAUDIT_SOURCE_DIR) / sourceRelative, to, fs::copy_options::overwrite_existing, ec);
}

// The contract: false comes with a message that names the input file.
inline void checkResult(bool ok, const std::string &err, const std::string &file) {
    if (ok) return;
    if (err.empty() || err.find(file) == std::string::npos) {
        std::fprintf(stderr, "fuzz: loader returned false with a message that does not name '%s': '%s'\n",
                     file.c_str(), err.c_str());
        std::abort();
    }
}

}  // namespace va::fuzz
