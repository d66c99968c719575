// Zip archives (Quake 3's .pk3 files are plain zip archives, members stored or deflated), read
// through libzip (docs/quake3.md, "Why libzip"). Expected failures return false with a message
// naming the archive, the member and a fix (STYLE 9, 10).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace va {

// Splits "ARCHIVE.pk3:MEMBER" (the extension matched case-insensitively; .zip works too) into the
// archive's path and the member's name. False when `path` names no archive member.
bool splitArchivePath(const std::string &path, std::string *archive, std::string *member);

// Reads member `member` of zip archive `archive` into *out. The member is looked up by exact name,
// then case-insensitively (Quake 3's file system ignores case). Its uncompressed size is checked
// against `maxBytes` before anything is allocated, and the bytes read must match it and the
// member's CRC-32 (libzip checks it).
bool readZipMember(const std::string &archive, const std::string &member, uint64_t maxBytes,
                   std::vector<uint8_t> *out, std::string *err);

// Names of the archive's members, in the archive's order.
bool listZipMembers(const std::string &archive, std::vector<std::string> *names, std::string *err);

// Writes a zip archive holding `members` (name, bytes), each deflated when `deflate` is true, else
// stored. Replaces an existing file. Used by the tests to make .pk3 files; also a small tool for
// packing generated maps.
struct ZipMember {
    std::string name;
    std::vector<uint8_t> bytes;
};
bool writeZipArchive(const std::string &archive, const std::vector<ZipMember> &members, bool deflate,
                     std::string *err);

}  // namespace va
