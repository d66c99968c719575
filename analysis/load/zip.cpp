// Zip archives through libzip: member lookup, a size check before allocating, a CRC-checked read.
#include "analysis/load/zip.h"

#include <algorithm>
#include <cctype>
#include <memory>

#include <zip.h>

namespace va {
namespace {

std::string lower(std::string s) {
    for (auto &c : s) c = char(std::tolower((unsigned char)c));
    return s;
}

// libzip's message for an error code from zip_open.
std::string openError(int code) {
    zip_error_t ze;
    zip_error_init_with_code(&ze, code);
    std::string m = zip_error_strerror(&ze);
    zip_error_fini(&ze);
    return m;
}

struct ArchiveCloser {
    void operator()(zip_t *z) const { zip_discard(z); }  // read-only: discard never writes
};
using Archive = std::unique_ptr<zip_t, ArchiveCloser>;

bool openArchive(const std::string &path, Archive *out, std::string *err) {
    int code = 0;
    zip_t *z = zip_open(path.c_str(), ZIP_RDONLY | ZIP_CHECKCONS, &code);
    if (!z) {
        *err = path + ": cannot open as a zip archive (" + openError(code) +
               "); a .pk3 must be a zip file: check the path, or test it with 'unzip -t'";
        return false;
    }
    out->reset(z);
    return true;
}

}  // namespace

bool splitArchivePath(const std::string &path, std::string *archive, std::string *member) {
    // The last ".pk3:" or ".zip:" separates the archive from the member (an archive's own path may
    // hold colons only before it).
    const std::string l = lower(path);
    size_t best = std::string::npos;
    for (const char *ext : {".pk3:", ".zip:"}) {
        const size_t p = l.rfind(ext);
        if (p != std::string::npos && (best == std::string::npos || p > best)) best = p;
    }
    if (best == std::string::npos) return false;
    *archive = path.substr(0, best + 4);
    *member = path.substr(best + 5);
    return true;
}

bool listZipMembers(const std::string &archivePath, std::vector<std::string> *names, std::string *err) {
    Archive z;
    if (!openArchive(archivePath, &z, err)) return false;
    const zip_int64_t n = zip_get_num_entries(z.get(), 0);
    names->clear();
    for (zip_int64_t i = 0; i < n; ++i) {
        const char *nm = zip_get_name(z.get(), zip_uint64_t(i), ZIP_FL_ENC_GUESS);
        if (nm) names->push_back(nm);
    }
    return true;
}

bool readZipMember(const std::string &archivePath, const std::string &member, uint64_t maxBytes,
                   std::vector<uint8_t> *out, std::string *err) {
    Archive z;
    if (!openArchive(archivePath, &z, err)) return false;
    const std::string where = archivePath + ":" + member;

    // Exact name first, then case-insensitive (as Quake 3's file system).
    zip_int64_t idx = zip_name_locate(z.get(), member.c_str(), 0);
    if (idx < 0) idx = zip_name_locate(z.get(), member.c_str(), ZIP_FL_NOCASE);
    if (idx < 0) {
        // Name the members with the same extension, so a typo is easy to fix.
        const std::string ext = lower(member.substr(std::min(member.size(), member.rfind('.'))));
        std::vector<std::string> like;
        const zip_int64_t n = zip_get_num_entries(z.get(), 0);
        for (zip_int64_t i = 0; i < n; ++i) {
            const char *nm = zip_get_name(z.get(), zip_uint64_t(i), ZIP_FL_ENC_GUESS);
            if (nm && !ext.empty() && lower(nm).size() >= ext.size() &&
                lower(nm).compare(lower(nm).size() - ext.size(), ext.size(), ext) == 0)
                like.push_back(nm);
        }
        std::string list;
        for (size_t i = 0; i < like.size() && i < 12; ++i) list += (i ? ", " : "") + like[i];
        if (like.size() > 12) list += ", ... (" + std::to_string(like.size()) + " in all)";
        *err = archivePath + ": no member '" + member + "' in the archive" +
               (like.empty() ? std::string("; list its members with 'unzip -l'")
                             : "; members ending in '" + ext + "': " + list);
        return false;
    }

    zip_stat_t st;
    zip_stat_init(&st);
    if (zip_stat_index(z.get(), zip_uint64_t(idx), 0, &st) != 0 || !(st.valid & ZIP_STAT_SIZE)) {
        *err = where + ": cannot read the member's size from the archive's directory (" +
               std::string(zip_strerror(z.get())) + "); the archive is damaged";
        return false;
    }
    // Checked before allocating: a hostile directory entry may claim any size.
    if (st.size > maxBytes) {
        *err = where + ": member is " + std::to_string(st.size) + " bytes uncompressed, more than the limit of " +
               std::to_string(maxBytes) + " bytes; this is not a map (or raise the limit)";
        return false;
    }

    zip_file_t *f = zip_fopen_index(z.get(), zip_uint64_t(idx), 0);
    if (!f) {
        *err = where + ": cannot open the member (" + std::string(zip_strerror(z.get())) +
               "); unsupported compression or a damaged archive (Quake 3 reads stored and deflated members)";
        return false;
    }
    out->assign(size_t(st.size), 0);
    uint64_t got = 0;
    bool ok = true;
    std::string why;
    while (got < st.size) {
        const zip_int64_t r = zip_fread(f, out->data() + got, st.size - got);
        if (r < 0) {
            ok = false;
            why = zip_file_strerror(f);
            break;
        }
        if (r == 0) break;
        got += uint64_t(r);
    }
    // A member that decompresses to more than its directory size, or fails its CRC at the end.
    if (ok && got == st.size) {
        uint8_t extra = 0;
        const zip_int64_t r = zip_fread(f, &extra, 1);
        if (r < 0) ok = false, why = zip_file_strerror(f);
        else if (r > 0) ok = false, why = "more data than the directory's size of " + std::to_string(st.size) + " bytes";
    }
    zip_fclose(f);
    if (!ok || got != st.size) {
        if (why.empty())
            why = "read " + std::to_string(got) + " of " + std::to_string(st.size) + " bytes";
        out->clear();
        *err = where + ": cannot decompress the member (" + why + "); the archive is damaged: fetch it again";
        return false;
    }
    return true;
}

bool writeZipArchive(const std::string &archivePath, const std::vector<ZipMember> &members, bool deflate,
                     std::string *err) {
    int code = 0;
    zip_t *z = zip_open(archivePath.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &code);
    if (!z) {
        *err = archivePath + ": cannot create the archive (" + openError(code) + ")";
        return false;
    }
    for (const auto &m : members) {
        // The buffer is not copied: `members` outlives zip_close below.
        zip_source_t *src = zip_source_buffer(z, m.bytes.data(), m.bytes.size(), 0);
        zip_int64_t idx = src ? zip_file_add(z, m.name.c_str(), src, ZIP_FL_OVERWRITE) : -1;
        if (idx < 0) {
            if (src) zip_source_free(src);
            *err = archivePath + ": cannot add '" + m.name + "' (" + zip_strerror(z) + ")";
            zip_discard(z);
            return false;
        }
        zip_set_file_compression(z, zip_uint64_t(idx), deflate ? ZIP_CM_DEFLATE : ZIP_CM_STORE, 0);
    }
    if (zip_close(z) != 0) {
        *err = archivePath + ": cannot write the archive (" + zip_strerror(z) + ")";
        zip_discard(z);
        return false;
    }
    return true;
}

}  // namespace va
