// Reading a glTF file before tinygltf parses it (see gltf_file.h).
#include "analysis/load/gltf_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string_view>

#include "common/json_util.h"

namespace va::gltf {
namespace {

using Json = nlohmann::json;

// Extensions visaudit honours when a file requires them: they change geometry, lights or the material
// flags, and the loader reads them (docs/scene-format.md, "glTF 2.0").
const std::vector<std::string> kHonoured = {
    "EXT_mesh_gpu_instancing", "EXT_meshopt_compression", "KHR_draco_mesh_compression", "KHR_lights_punctual",
    "KHR_materials_ior",       "KHR_materials_transmission", "KHR_mesh_quantization"};
// Extensions that change only what visaudit never reads (textures, shading, metadata, animation):
// a file that requires them is analysed as it is, since they change no triangle.
const std::vector<std::string> kAppearanceOnly = {
    "EXT_lights_image_based",  "EXT_texture_avif",       "EXT_texture_webp",
    "KHR_animation_pointer",   "KHR_materials_anisotropy", "KHR_materials_clearcoat",
    "KHR_materials_diffuse_transmission", "KHR_materials_dispersion", "KHR_materials_emissive_strength",
    "KHR_materials_iridescence", "KHR_materials_pbrSpecularGlossiness", "KHR_materials_sheen",
    "KHR_materials_specular",  "KHR_materials_unlit",    "KHR_materials_variants",
    "KHR_materials_volume",    "KHR_texture_basisu",     "KHR_texture_transform",
    "KHR_xmp",                 "KHR_xmp_json_ld",        "MSFT_texture_dds"};

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;  // "JSON"

uint32_t read32(const unsigned char *p) {
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
void put32(std::vector<unsigned char> &v, uint32_t x) {
    for (int i = 0; i < 4; ++i) v.push_back(static_cast<unsigned char>(x >> (8 * i)));
}

const char *kConvert =
    "visaudit reads glTF 2.0: convert the file first, e.g. with gltf-pipeline (npm: "
    "'npx gltf-pipeline -i in.gltf -o out.gltf' upgrades glTF 1.0 to 2.0), or export it again as glTF 2.0";

// "2.0" -> 2, 0; false when the text is not MAJOR.MINOR.
bool parseVersion(const std::string &s, int *major, int *minor) {
    const size_t dot = s.find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 >= s.size()) return false;
    for (size_t i = 0; i < s.size(); ++i)
        if (i != dot && !(s[i] >= '0' && s[i] <= '9')) return false;
    if (dot > 4 || s.size() - dot - 1 > 4) return false;
    *major = std::stoi(s.substr(0, dot));
    *minor = std::stoi(s.substr(dot + 1));
    return true;
}

// Refuses glTF 1.0 and versions newer than 2.x (glTF 2.0, "Versioning": a 2.0 loader reads any 2.x
// file whose minVersion it meets).
bool checkVersion(const std::string &path, const Json &root, std::string *err) {
    auto it = root.find("asset");
    if (it == root.end() || !it->is_object()) {
        // glTF 1.0 kept its top-level collections as objects keyed by id; 2.0 has arrays.
        for (const char *key : {"meshes", "nodes", "accessors", "buffers", "bufferViews", "scenes", "materials"}) {
            auto c = root.find(key);
            if (c != root.end() && c->is_object()) {
                *err = path + ": this is glTF 1.0 (its \"" + key +
                       "\" is an object keyed by id; glTF 2.0 has arrays and an \"asset\" with \"version\": \"2.0\"); " +
                       kConvert;
                return false;
            }
        }
        return true;  // tinygltf says what is missing
    }
    auto v = it->find("version");
    if (v == it->end() || !v->is_string()) return true;  // tinygltf says what is missing
    const std::string version = v->get<std::string>();
    int major = 0, minor = 0;
    if (!parseVersion(version, &major, &minor)) {
        *err = path + ": asset.version \"" + version + "\" is not a glTF version (MAJOR.MINOR, \"2.0\")";
        return false;
    }
    if (major < 2) {
        *err = path + ": glTF " + version + " (asset.version \"" + version + "\") is not supported; " + kConvert;
        return false;
    }
    if (major > 2) {
        *err = path + ": glTF " + version + " (asset.version \"" + version +
               "\") is newer than glTF 2.0, the version visaudit reads; export the file as glTF 2.0";
        return false;
    }
    auto mv = it->find("minVersion");
    if (mv != it->end() && mv->is_string()) {
        const std::string minVersion = mv->get<std::string>();
        int mmaj = 0, mmin = 0;
        if (!parseVersion(minVersion, &mmaj, &mmin) || mmaj != 2 || mmin > 0) {
            *err = path + ": the file needs a glTF " + minVersion + " loader (asset.minVersion \"" + minVersion +
                   "\"); visaudit reads glTF 2.0; export the file for glTF 2.0";
            return false;
        }
    }
    return true;
}

bool checkRequiredExtensions(const std::string &path, const Json &root, std::string *err) {
    auto req = root.find("extensionsRequired");
    if (req == root.end() || !req->is_array()) return true;
    for (const auto &e : *req) {
        if (!e.is_string()) continue;
        const std::string name = e.get<std::string>();
        if (std::find(kHonoured.begin(), kHonoured.end(), name) != kHonoured.end() ||
            std::find(kAppearanceOnly.begin(), kAppearanceOnly.end(), name) != kAppearanceOnly.end())
            continue;
        *err = path + ": the file requires the glTF extension '" + name +
               "' (extensionsRequired), which visaudit cannot honour; it may change the geometry, so the "
               "file is refused rather than analysed without it. visaudit honours " +
               json::joinList(kHonoured) +
               " and ignores extensions that change only textures and shading; export the file without '" + name + "'";
        return false;
    }
    return true;
}

// Takes what tinygltf 2.7 cannot parse out of the JSON (see gltf_file.h); true when it changed it.
bool moveOutOfTinygltfsWay(Json &root, Source *out) {
    bool changed = false;
    auto meshes = root.find("meshes");
    if (meshes != root.end() && meshes->is_array()) {
        for (size_t m = 0; m < meshes->size(); ++m) {
            Json &mesh = (*meshes)[m];
            if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
            Json &prims = mesh["primitives"];
            for (size_t p = 0; p < prims.size(); ++p) {
                Json &prim = prims[p];
                if (!prim.is_object()) continue;
                auto ext = prim.find("extensions");
                if (ext == prim.end() || !ext->is_object() || !ext->contains("KHR_draco_mesh_compression")) continue;
                auto ind = prim.find("indices");
                if (ind == prim.end() || !ind->is_number_integer()) continue;
                const int64_t a = ind->get<int64_t>();
                if (a < 0 || a > INT32_MAX) continue;  // tinygltf refuses it as before
                out->dracoIndices[{int(m), int(p)}] = int(a);
                prim.erase(ind);
                changed = true;
            }
        }
    }
    auto buffers = root.find("buffers");
    if (buffers != root.end() && buffers->is_array()) {
        for (Json &b : *buffers) {
            if (!b.is_object() || b.contains("uri")) continue;
            auto ext = b.find("extensions");
            if (ext == b.end() || !ext->is_object()) continue;
            auto mo = ext->find("EXT_meshopt_compression");
            if (mo == ext->end() || !mo->is_object()) continue;
            auto fb = mo->find("fallback");
            if (fb == mo->end() || !fb->is_boolean() || !fb->get<bool>()) continue;
            // A one-byte buffer in its place (tinygltf decodes no empty data URI): only compressed
            // views refer to it, and those are decoded from their own buffer (EXT_meshopt_compression,
            // "fallback buffers").
            b["uri"] = "data:application/octet-stream;base64,AA==";
            b["byteLength"] = 1;
            changed = true;
        }
    }
    return changed;
}

}  // namespace

bool prepareSource(const std::string &path, bool binary, uint64_t maxJsonDepth, Source *out, std::string *err) {
    auto fail = [&](const std::string &m) {
        *err = m;
        return false;
    };
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) return fail(path + ": cannot read the file: " + ec.message());
    // tinygltf takes 32-bit sizes, and a GLB's length field is 32 bits (glTF 2.0, "Binary glTF Layout").
    if (size >= (uintmax_t(1) << 32))
        return fail(path + ": the file is " + std::to_string(size) +
                    " bytes, more than the 4 GiB a glTF JSON or GLB file may hold; keep large buffers in "
                    "external .bin files");
    std::ifstream f(path, std::ios::binary);
    if (!f) return fail(path + ": cannot open the file for reading (check its permissions)");
    out->bytes.resize(size_t(size));
    if (size > 0 && !f.read(reinterpret_cast<char *>(out->bytes.data()), std::streamsize(size)))
        return fail(path + ": cannot read the file");
    out->binary = binary;
    const size_t slash = path.find_last_of("/\\");
    out->baseDir = slash == std::string::npos ? "" : path.substr(0, slash);

    // Where the JSON is: the whole file, or a GLB's first chunk. A GLB whose header does not hold
    // together goes to tinygltf unchanged, which says what is wrong with it.
    const unsigned char *b = out->bytes.data();
    size_t jsonBegin = 0, jsonSize = out->bytes.size();
    if (binary) {
        if (out->bytes.size() < 20 || read32(b) != kGlbMagic) return true;
        const uint32_t version = read32(b + 4);
        if (version == 1)
            return fail(path + ": binary glTF version 1 (glTF 1.0 with KHR_binary_glTF) is not supported; " + kConvert);
        if (version != 2)
            return fail(path + ": binary glTF container version " + std::to_string(version) +
                        " is not supported (glTF 2.0's is 2); export the file as glTF 2.0");
        const uint32_t chunkLength = read32(b + 12);
        if (read32(b + 16) != kChunkJson || uint64_t(chunkLength) + 20 > out->bytes.size()) return true;
        jsonBegin = 20;
        jsonSize = chunkLength;
    }
    const char *text = reinterpret_cast<const char *>(b) + jsonBegin;

    // Nesting before parsing: tinygltf converts extras and extensions recursively.
    if (!json::checkDepth(std::string_view(text, jsonSize), binary ? path + " (JSON chunk)" : path, maxJsonDepth, err))
        return false;

    Json root = Json::parse(text, text + jsonSize, nullptr, /*allow_exceptions=*/false);
    if (root.is_discarded() || !root.is_object()) return true;  // tinygltf says where the syntax is wrong
    if (!checkVersion(path, root, err)) return false;
    if (!checkRequiredExtensions(path, root, err)) return false;
    if (!moveOutOfTinygltfsWay(root, out)) return true;

    // The JSON again, without what was moved out (invalid UTF-8 in strings replaced: tinygltf would
    // read it as it is, and visaudit uses no string but names).
    std::string json = root.dump(-1, ' ', false, Json::error_handler_t::replace);
    if (!binary) {
        out->bytes.assign(json.begin(), json.end());
        return true;
    }
    // A GLB again: header, the new JSON chunk (padded with spaces to 4 bytes), then the rest of the
    // file as it was (the BIN chunk).
    while (json.size() % 4 != 0) json.push_back(' ');
    const size_t restBegin = 20 + size_t(jsonSize);
    const size_t declared = read32(b + 8);
    const size_t restEnd = std::max(restBegin, std::min(declared, out->bytes.size()));
    std::vector<unsigned char> glb;
    glb.reserve(20 + json.size() + (restEnd - restBegin));
    put32(glb, kGlbMagic);
    put32(glb, 2);
    put32(glb, uint32_t(20 + json.size() + (restEnd - restBegin)));
    put32(glb, uint32_t(json.size()));
    put32(glb, kChunkJson);
    glb.insert(glb.end(), json.begin(), json.end());
    glb.insert(glb.end(), out->bytes.begin() + std::ptrdiff_t(restBegin), out->bytes.begin() + std::ptrdiff_t(restEnd));
    out->bytes = std::move(glb);
    return true;
}

}  // namespace va::gltf
