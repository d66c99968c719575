// pvs-audit.json, pvs-audit.png, pvs-audit.html and the console summary (reports/pvs_audit_report.h).
#include "reports/pvs_audit_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numeric>

#include "reports/html.h"
#include "reports/html_assets.h"
#include "reports/legend.h"
#include "reports/report.h"

namespace va {

namespace {

using Json = nlohmann::ordered_json;

const char *kImageName = "pvs-audit.png";
const char *kMissBins[] = {"0", "1", "2-3", "4-7", "8-15", "16-31", "32+"};

Json vec(Vec3 v) { return Json::array({v.x, v.y, v.z}); }

// Clusters ordered worst first by a key (ties: lower cluster first); only those with key > 0.
template <class Key>
std::vector<const PvsClusterAudit *> worst(const PvsAuditResult &r, Key key, size_t n) {
    std::vector<const PvsClusterAudit *> v;
    for (const PvsClusterAudit &c : r.clusters)
        if (c.samples > 0 && key(c) > 0) v.push_back(&c);
    std::stable_sort(v.begin(), v.end(), [&](const PvsClusterAudit *a, const PvsClusterAudit *b) { return key(*a) > key(*b); });
    if (v.size() > n) v.resize(n);
    return v;
}
double slackKey(const PvsClusterAudit &c) { return double(c.slack); }
double missKey(const PvsClusterAudit &c) { return double(c.misses); }

Json clusterSummary(const PvsClusterAudit &c) {
    Json j;
    j["cluster"] = c.cluster;
    j["misses"] = c.misses;
    j["crack_misses"] = c.crackMisses;
    j["slack"] = c.slack;
    j["pvs_visible"] = c.pvsVisible;
    j["seen"] = c.seen;
    j["slack_share"] = c.slackShare();
    j["position"] = c.eyes.empty() ? Json(nullptr) : vec(c.eyes[0]);
    j["center"] = c.bounds.empty() ? Json(nullptr) : vec(c.bounds.center());
    return j;
}

Json missJson(const PvsMiss &m) {
    Json j;
    j["from"] = m.from;
    j["to"] = m.to;
    j["sample"] = m.sample;
    j["eye"] = vec(m.eye);
    j["player_eye"] = m.playerEye;
    j["direction"] = vec(m.direction);
    j["eye_leaf"] = m.eyeLeaf;
    j["leaf"] = m.leaf;
    j["enter"] = m.enter;
    j["exit"] = m.exit;
    j["stop"] = m.stop;
    j["stopped_by"] = pvsStopName(m.stoppedBy);
    j["stop_triangle"] = m.stoppedBy == PvsStop::surface && m.stopTriangle != 0xFFFFFFFFu ? Json(m.stopTriangle) : Json(nullptr);
    j["stop_face"] = m.stoppedBy == PvsStop::surface && m.stopFace != 0xFFFFFFFFu ? Json(m.stopFace) : Json(nullptr);
    j["stop_leaf"] = m.stoppedBy == PvsStop::solid ? Json(m.stopLeaf) : Json(nullptr);
    j["rays"] = m.rays;
    j["pvs_byte"] = m.pvsByte;
    j["pvs_bit"] = m.pvsBit;
    j["pvs_byte_value"] = m.pvsByteValue;
    return j;
}

// ---- The image --------------------------------------------------------------------------------

constexpr Rgb8 kBackground{16, 16, 16}, kMiss{235, 30, 30}, kRay{255, 255, 255}, kEye{255, 220, 0};
// Slack share 0 -> green, 0.5 -> teal, 1 -> blue.
Rgb8 slackColor(double s) {
    const Rgb8 stops[3] = {{60, 180, 75}, {40, 160, 170}, {70, 90, 235}};
    s = std::clamp(s, 0.0, 1.0) * 2;
    const int i = std::min(1, int(s));
    const double f = s - i;
    auto mix = [&](uint8_t a, uint8_t b) { return uint8_t(std::lround(a + (b - a) * f)); };
    return {mix(stops[i].r, stops[i + 1].r), mix(stops[i].g, stops[i + 1].g), mix(stops[i].b, stops[i + 1].b)};
}

void plot(std::vector<uint8_t> &rgb, int w, int h, int x, int y, Rgb8 c) {
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    uint8_t *p = &rgb[(size_t(y) * w + x) * 3];
    p[0] = c.r, p[1] = c.g, p[2] = c.b;
}
// Bresenham between integer pixel centers.
void line(std::vector<uint8_t> &rgb, int w, int h, int x0, int y0, int x1, int y1, Rgb8 c) {
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0), sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    for (int guard = 0; guard <= dx - dy; ++guard) {
        plot(rgb, w, h, x0, y0, c);
        if (x0 == x1 && y0 == y1) break;
        const int e2 = 2 * err;
        if (e2 >= dy) err += dy, x0 += sx;
        if (e2 <= dx) err += dx, y0 += sy;
    }
}

// ---- Formatting ---------------------------------------------------------------------------------

std::string fmt(const char *f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}
std::string count(uint64_t v) {
    std::string d = std::to_string(v), o;
    for (size_t i = 0; i < d.size(); ++i) {
        if (i > 0 && (d.size() - i) % 3 == 0) o += ',';
        o += d[i];
    }
    return o;
}
std::string hexByte(int v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%02x", unsigned(v) & 0xFFu);
    return b;
}
std::string percent(double share) { return fmt("%.1f%%", 100 * share); }
std::string pos(Vec3 p) {
    char b[96];
    std::snprintf(b, sizeof b, "(%.0f, %.0f, %.0f)", p.x, p.y, p.z);
    return b;
}

// Reading pvs-audit.json without exceptions (the page is made from the JSON alone).
const Json *at(const Json &j, std::initializer_list<const char *> keys) {
    const Json *x = &j;
    for (const char *k : keys) {
        if (!x->is_object() || !x->contains(k)) return nullptr;
        x = &(*x)[k];
    }
    return x;
}
double num(const Json &j, std::initializer_list<const char *> keys, double fallback = 0) {
    const Json *x = at(j, keys);
    return x && x->is_number() ? x->get<double>() : fallback;
}
std::string text(const Json &j, std::initializer_list<const char *> keys) {
    const Json *x = at(j, keys);
    return x && x->is_string() ? x->get<std::string>() : std::string();
}
bool isTrueAt(const Json &j, const char *key) {
    const Json *x = at(j, {key});
    return x && x->is_boolean() && x->get<bool>();
}
std::string jpos(const Json *p) {
    if (!p || !p->is_array() || p->size() != 3 || !(*p)[0].is_number()) return "—";
    return pos({(*p)[0].get<double>(), (*p)[1].get<double>(), (*p)[2].get<double>()});
}

}  // namespace

Json pvsAuditJson(const PvsAuditResult &r, const std::string &imageName) {
    Json j;
    j["format"] = kPvsAuditFormat;
    j["tool"] = {{"name", "visaudit"}, {"version", VISAUDIT_VERSION}};
    j["map"] = r.map;
    Json s;
    s["samples"] = r.settings.samples;
    s["resolution"] = r.settings.resolution;
    s["rays_per_sample"] = r.raysPerSample;
    s["seed"] = r.settings.seed;
    s["clusters"] = r.settings.clusters.empty() ? Json("all") : Json(r.settings.clusters);
    s["image_size"] = r.settings.imageSize;
    j["settings"] = s;
    j["far_plane"] = {{"distance", r.farPlane > 0 ? Json(r.farPlane) : Json(nullptr)},
                      {"source", r.farPlaneSource},
                      {"text", r.farPlaneText}};
    j["definition"] = {{"tolerance", r.tolerance}, {"map_diagonal", r.mapDiagonal}, {"pvs_row_bytes", r.pvsRowBytes}};
    j["occluders"] = {{"opaque_triangles", r.occluders.opaque},
                      {"translucent_triangles", r.occluders.translucent},
                      {"entity_triangles", r.occluders.entity}};
    const PvsAuditTotals &t = r.totals;
    j["totals"] = {{"clusters", t.clusters},
                   {"requested", t.requested},
                   {"audited", t.audited},
                   {"unsampled", t.unsampled},
                   {"samples", t.samples},
                   {"rays", t.rays},
                   {"pvs_visible_pairs", t.pvsVisiblePairs},
                   {"seen_pairs", t.seenPairs},
                   {"misses", t.misses},
                   {"miss_clusters", t.missClusters},
                   {"crack_misses", t.crackMisses},
                   {"player_clusters", t.playerClusters},
                   {"slack_pairs", t.slackPairs},
                   {"slack_share", t.slackShare},
                   {"seen_beyond_far_pairs", t.seenBeyondFarPairs},
                   {"hidden_by_far_plane_pairs", t.hiddenByFarPlanePairs}};
    Json sh = Json::array(), mh = Json::array();
    for (size_t k = 0; k < r.slackHistogram.size(); ++k)
        sh.push_back({{"bin", fmt("%.0f", 10.0 * k) + "-" + fmt("%.0f", 10.0 * (k + 1)) + "%"}, {"clusters", r.slackHistogram[k]}});
    for (size_t k = 0; k < r.missHistogram.size(); ++k)
        mh.push_back({{"bin", kMissBins[k]}, {"clusters", r.missHistogram[k]}});
    j["histograms"] = {{"slack_share", sh}, {"misses", mh}};
    Json wm = Json::array(), ws = Json::array();
    for (const PvsClusterAudit *c : worst(r, missKey, kPvsAuditWorst)) wm.push_back(clusterSummary(*c));
    for (const PvsClusterAudit *c : worst(r, slackKey, kPvsAuditWorst)) ws.push_back(clusterSummary(*c));
    j["worst"] = {{"misses", wm}, {"slack", ws}};
    Json misses = Json::array();
    for (const PvsClusterAudit &c : r.clusters)
        for (const PvsMiss &m : c.missList)
            if (misses.size() < kPvsAuditMaxListedMisses) misses.push_back(missJson(m));
    j["misses_listed"] = misses.size();
    j["misses"] = misses;
    Json cl = Json::array();
    for (const PvsClusterAudit &c : r.clusters) {
        Json e;
        e["cluster"] = c.cluster;
        e["leafs"] = c.leafs;
        e["samples"] = c.samples;
        e["attempts"] = c.attempts;
        e["rejected_other"] = c.rejectedOther;
        e["rejected_solid"] = c.rejectedSolid;
        e["player_samples"] = c.playerSamples;
        e["rays"] = c.rays;
        e["pvs_visible"] = c.pvsVisible;
        e["seen"] = c.seen;
        e["misses"] = c.misses;
        e["crack_misses"] = c.crackMisses;
        e["slack"] = c.slack;
        e["slack_share"] = c.slackShare();
        e["seen_beyond_far"] = c.seenBeyondFar;
        e["hidden_by_far_plane"] = c.hiddenByFarPlane;
        e["eye"] = c.eyes.empty() ? Json(nullptr) : vec(c.eyes[0]);
        e["bounds"] = c.bounds.empty() ? Json(nullptr) : Json({{"min", vec(c.bounds.lo)}, {"max", vec(c.bounds.hi)}});
        cl.push_back(e);
    }
    j["clusters"] = cl;
    j["image"] = imageName.empty() ? Json(nullptr) : Json(imageName);
    j["timings_ms"] = {{"setup", r.setupMs},
                       {"audit", r.auditMs},
                       {"top_view", r.topViewMs},
                       {"thread_samples", r.sampleThreadMs},
                       {"thread_rays", r.castThreadMs},
                       {"thread_walk", r.walkThreadMs}};
    return j;
}

std::string pvsAuditTable(const PvsAuditResult &r) {
    const PvsAuditTotals &t = r.totals;
    std::string o;
    o += "PVS audit of " + r.map + ": " + count(t.audited) + " of " + count(t.requested) + " clusters audited (" +
         count(t.clusters) + " in the map), " + count(t.samples) + " eye points, " + count(t.rays) + " rays\n";
    o += "  far plane   " + (r.farPlane > 0 ? fmt("%g", r.farPlane) + " (" + r.farPlaneSource + ")" : std::string("none (unlimited)")) + "\n";
    o += "  misses      " + count(t.misses) + " cluster pairs a player's eye sees although the PVS says hidden, from " +
         count(t.missClusters) + " clusters (best 0)\n";
    if (t.crackMisses)
        o += "  cracks      " + count(t.crackMisses) + " more pairs seen with the PVS bit 0 only from points no player's "
             "eye reaches (not misses)\n";
    o += "  player eye  " + count(t.playerClusters) + " of the audited clusters have eye points where a player's eye can be\n";
    o += "  slack       " + count(t.slackPairs) + " of " + count(t.pvsVisiblePairs) + " PVS-visible pairs never seen (" +
         percent(t.slackShare) + ")\n";
    if (r.farPlane > 0)
        o += "  beyond far  " + count(t.seenBeyondFarPairs) + " pairs seen only beyond the far plane, " +
             count(t.hiddenByFarPlanePairs) + " of them left out of the PVS by design\n";
    if (t.unsampled) o += "  unsampled   " + count(t.unsampled) + " clusters had no eye point (not audited)\n";
    o += "  time        " + fmt("%.0f", r.auditMs) + " ms for the clusters (threads: " + fmt("%.0f", r.sampleThreadMs) +
         " ms eye points, " + fmt("%.0f", r.castThreadMs) + " ms Embree, " + fmt("%.0f", r.walkThreadMs) + " ms BSP walk)\n";
    const auto wm = worst(r, missKey, 5), ws = worst(r, slackKey, 5);
    for (const PvsClusterAudit *c : wm)
        o += "  worst miss  cluster " + std::to_string(c->cluster) + ": " + std::to_string(c->misses) + " misses, eye " +
             pos(c->eyes[0]) + "\n";
    for (const PvsClusterAudit *c : ws)
        o += "  worst slack cluster " + std::to_string(c->cluster) + ": " + std::to_string(c->slack) + " of " +
             std::to_string(c->pvsVisible) + " visible never seen, eye " + pos(c->eyes[0]) + "\n";
    size_t shown = 0;
    for (const PvsClusterAudit &c : r.clusters)
        for (const PvsMiss &m : c.missList) {
            if (shown >= 5) break;
            if (!m.playerEye) continue;
            ++shown;
            o += "  miss        " + std::to_string(m.from) + " -> " + std::to_string(m.to) + ": eye " + pos(m.eye) +
                 ", entered leaf " + std::to_string(m.leaf) + " at " + fmt("%.1f", m.enter) + " units, PVS byte " +
                 std::to_string(m.pvsByte) + " bit " + std::to_string(m.pvsBit) + " = 0\n";
        }
    return o;
}

bool pvsAuditImage(const PvsAuditResult &r, std::vector<uint8_t> *out, int *width, int *height) {
    const PvsTopView &v = r.top;
    if (v.width <= 0 || v.height <= 0) return false;
    // Per cluster: its color (audited ones only).
    std::vector<int8_t> state(size_t(std::max(0, r.clusterCount)), 0);  // 0 not audited, 1 audited
    std::vector<Rgb8> color(state.size());
    for (const PvsClusterAudit &c : r.clusters) {
        if (c.samples == 0) continue;
        state[size_t(c.cluster)] = 1;
        color[size_t(c.cluster)] = c.misses > 0 ? kMiss : slackColor(c.slackShare());
    }
    const int W = v.width, H = v.height;
    // The geometry's gray: height (higher is lighter) and slope (floors full, steep faces darker),
    // darkened where the height jumps by more than a step (a player climbs 18 units): the walls'
    // outlines.
    double zLo = INFINITY, zHi = -INFINITY;
    for (float z : v.surfaceZ)
        if (std::isfinite(z)) zLo = std::min(zLo, double(z)), zHi = std::max(zHi, double(z));
    auto heightAt = [&](int x, int y) { return v.surfaceZ[size_t(y) * W + x]; };
    std::vector<uint8_t> rgb(size_t(W) * H * 3);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t p = size_t(y) * W + x;
            Rgb8 c = kBackground;
            const float z = v.surfaceZ[p];
            if (std::isfinite(z)) {
                const double hf = zHi > zLo ? (z - zLo) / (zHi - zLo) : 1.0;
                double shade = 0.35 + 0.4 * hf + 0.25 * v.slope[p];
                for (const auto &[dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
                    const int nx = x + dx, ny = y + dy;
                    if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                    const float n = heightAt(nx, ny);
                    if (!std::isfinite(n) || std::fabs(n - z) > 18) {
                        shade *= 0.55;
                        break;
                    }
                }
                const int32_t cl = v.cluster[p];
                Rgb8 k{200, 200, 200};
                if (cl >= 0 && size_t(cl) < state.size() && state[size_t(cl)]) k = color[size_t(cl)];
                c = {uint8_t(std::lround(k.r * shade)), uint8_t(std::lround(k.g * shade)), uint8_t(std::lround(k.b * shade))};
            }
            rgb[3 * p] = c.r, rgb[3 * p + 1] = c.g, rgb[3 * p + 2] = c.b;
        }
    // The misses' rays, eye to where they entered the missed cluster, and the eyes (first 200).
    size_t drawn = 0;
    for (const PvsClusterAudit &c : r.clusters)
        for (const PvsMiss &m : c.missList) {
            if (!m.playerEye) continue;
            if (drawn++ >= 200) break;
            const Vec3 e = m.eye + m.direction * m.enter;
            const int x0 = int(std::floor(v.column(m.eye.x))), y0 = int(std::floor(v.row(m.eye.y)));
            const int x1 = int(std::floor(v.column(e.x))), y1 = int(std::floor(v.row(e.y)));
            line(rgb, W, H, x0, y0, x1, y1, kRay);
            for (int d = -2; d <= 2; ++d) plot(rgb, W, H, x0 + d, y0, kEye), plot(rgb, W, H, x0, y0 + d, kEye);
        }
    const std::vector<LegendEntry> legend = {
        {kMiss, "misses (PVS hides a cluster it sees)"}, {slackColor(0), "slack 0%"}, {slackColor(0.5), "slack 50%"},
        {slackColor(1), "slack 100%"}, {{150, 150, 150}, "not audited"}, {kRay, "miss ray: eye to the cluster"},
        {kEye, "eye point"}};
    int canvasH = 0;
    *out = withLegend(rgb, W, H, legend, &canvasH);
    *width = W;
    *height = canvasH;
    return true;
}

namespace {
// The totals, each with its meaning; the far plane, the sampling, the occluders and the time.
std::string pvsTotalsSection(const Json &a) {
    std::string o;
    struct Row {
        const char *key, *meaning;
    };
    static const Row rows[] = {
        {"clusters", "clusters in the map (PVS rows)"},
        {"requested", "clusters asked for"},
        {"audited", "of those, clusters with at least one eye point"},
        {"unsampled", "clusters where no eye point was found (not audited; best 0)"},
        {"samples", "eye points"},
        {"rays", "rays cast"},
        {"pvs_visible_pairs", "PVS bits set in the audited rows"},
        {"seen_pairs", "cluster pairs seen within the far plane"},
        {"misses", "pairs seen within the far plane from a point where a player's eye can be, although the PVS bit is 0 (best 0)"},
        {"miss_clusters", "clusters with at least one miss (best 0)"},
        {"crack_misses", "pairs seen with PVS bit 0 only from points no player's eye reaches (not misses)"},
        {"player_clusters", "audited clusters with eye points where a player's eye can be"},
        {"slack_pairs", "pairs the PVS marks visible that no eye point saw"},
        {"slack_share", "slack pairs / PVS-visible pairs (lower is tighter; an upper bound)"},
        {"seen_beyond_far_pairs", "pairs seen only beyond the far plane"},
        {"hidden_by_far_plane_pairs", "of those, left out of the PVS by the far plane (by design)"},
    };
    o += "<section class=\"block\" id=\"totals\"><h2>Totals</h2><table>";
    for (const Row &r : rows) {
        const Json *v = at(a, {"totals", r.key});
        std::string val = "—";
        if (v && v->is_number()) val = std::string(r.key) == "slack_share" ? percent(v->get<double>()) : count(v->get<uint64_t>());
        o += "<tr><th>" + std::string(r.key) + "</th><td class=\"n\">" + val + "</td><td class=\"muted\">" + r.meaning + "</td></tr>";
    }
    o += "</table>";
    const Json *fp = at(a, {"far_plane", "distance"});
    o += "<p>Far plane: " +
         (fp && fp->is_number() ? fmt("%g", fp->get<double>()) + " units (" + htmlEscape(text(a, {"far_plane", "source"})) + ")"
                                : std::string("none (unlimited)")) +
         ". Eye points per cluster " + fmt("%.0f", num(a, {"settings", "samples"})) + ", rays per eye point " +
         fmt("%.0f", num(a, {"settings", "rays_per_sample"})) + " (cube faces of " + fmt("%.0f", num(a, {"settings", "resolution"})) +
         "²), seed " + fmt("%.0f", num(a, {"settings", "seed"})) + "; a leaf counts when a ray stays in it longer than " +
         fmt("%.3g", num(a, {"definition", "tolerance"})) + " units. Occluders: " +
         count(uint64_t(num(a, {"occluders", "opaque_triangles"}))) + " opaque world triangles; passed: " +
         count(uint64_t(num(a, {"occluders", "translucent_triangles"}))) + " translucent, " +
         count(uint64_t(num(a, {"occluders", "entity_triangles"}))) + " of brush entities.</p>";
    o += "<p class=\"muted\">Time: " + fmt("%.0f", num(a, {"timings_ms", "audit"})) + " ms for the clusters (threads: " +
         fmt("%.0f", num(a, {"timings_ms", "thread_samples"})) + " ms eye points, " +
         fmt("%.0f", num(a, {"timings_ms", "thread_rays"})) + " ms Embree, " + fmt("%.0f", num(a, {"timings_ms", "thread_walk"})) +
         " ms BSP walk), " + fmt("%.0f", num(a, {"timings_ms", "top_view"})) + " ms for the map image.</p></section>\n";
    return o;
}

// The top-down image, when the folder holds it.
std::string pvsImageSection(const Json &a, const std::string &dir) {
    std::string o;
    const Json *img = at(a, {"image"});
    if (img && img->is_string() && std::filesystem::exists(std::filesystem::path(dir) / img->get<std::string>())) {
        const std::string name = htmlEscape(img->get<std::string>());
        o += "<section class=\"block\" id=\"map\"><h2>The level from above</h2><figure><a class=\"imgwrap\" href=\"" + name +
             "\"><img src=\"" + name + "\" alt=\"top-down map colored by slack and misses\"></a><figcaption>Each surface seen "
             "from above is colored by the cluster a player standing on it is in: <b>red</b> a cluster with misses, green to "
             "blue its slack share (0% to 100%), gray a cluster not audited. White lines: the first rays that saw a missed "
             "cluster, from the eye (yellow cross) to where they entered it.</figcaption></figure></section>\n";
    }
    return o;
}

// The slack and miss histograms of the audited clusters, as bars.
std::string pvsHistogramSection(const Json &a) {
    std::string o;
    auto histogram = [&](const char *key, const char *title) {
        const Json *h = at(a, {"histograms", key});
        if (!h || !h->is_array()) return;
        double most = 1;
        for (const Json &b : *h) most = std::max(most, num(b, {"clusters"}));
        o += std::string("<h3>") + title + "</h3><table>";
        for (const Json &b : *h) {
            const double n = num(b, {"clusters"});
            o += "<tr><th>" + htmlEscape(text(b, {"bin"})) + "</th><td class=\"n\">" + count(uint64_t(n)) +
                 "</td><td><span class=\"swatch\" style=\"width:" + fmt("%.0f", 300 * n / most) +
                 "px;background:var(--accent)\"></span></td></tr>";
        }
        o += "</table>";
    };
    o += "<section class=\"block\" id=\"histograms\"><h2>Histograms (audited clusters)</h2>";
    histogram("slack_share", "Slack share per cluster");
    histogram("misses", "Misses per cluster");
    o += "</section>\n";
    return o;
}

// The clusters with the most misses and the most slack.
std::string pvsWorstSection(const Json &a) {
    std::string o;
    auto worstTable = [&](const char *key, const char *title) {
        const Json *w = at(a, {"worst", key});
        o += std::string("<h3>") + title + "</h3>";
        if (!w || !w->is_array() || w->empty()) {
            o += "<p class=\"muted\">none</p>";
            return;
        }
        o += "<table><tr><th class=\"n\">cluster</th><th class=\"n\">misses</th><th class=\"n\">slack</th><th class=\"n\">PVS "
             "visible</th><th class=\"n\">seen</th><th>first eye point</th><th>center of its leafs</th></tr>";
        for (const Json &c : *w)
            o += "<tr><td class=\"n\">" + fmt("%.0f", num(c, {"cluster"})) + "</td><td class=\"n\">" + fmt("%.0f", num(c, {"misses"})) +
                 "</td><td class=\"n\">" + fmt("%.0f", num(c, {"slack"})) + "</td><td class=\"n\">" +
                 fmt("%.0f", num(c, {"pvs_visible"})) + "</td><td class=\"n\">" + fmt("%.0f", num(c, {"seen"})) + "</td><td>" +
                 jpos(at(c, {"position"})) + "</td><td>" + jpos(at(c, {"center"})) + "</td></tr>";
        o += "</table>";
    };
    o += "<section class=\"block\" id=\"worst\"><h2>Worst clusters</h2>";
    worstTable("misses", "Most misses");
    worstTable("slack", "Most slack");
    o += "</section>\n";
    return o;
}

// Every miss (the first 100) with the evidence that proves it.
std::string pvsMissesSection(const Json &a) {
    std::string o;
    o += "<section class=\"block\" id=\"misses\"><h2>Misses and their evidence</h2>";
    const Json *ms = at(a, {"misses"});
    if (!ms || !ms->is_array() || ms->empty()) {
        o += "<p class=\"good\">No cluster was seen that its PVS row hides, from any eye point.</p>";
    } else {
        o += "<p>Each row: a ray from an eye point of cluster <i>from</i> passed through leaf <i>leaf</i> of cluster "
             "<i>to</i> between distances <i>enter</i> and <i>exit</i> before it stopped, while bit <i>to</i>&amp;7 of PVS "
             "byte <i>from</i>·row bytes + <i>to</i>/8 is 0. <i>player eye</i> no: a crack miss, seen only from points "
             "no player's eye reaches (not counted as a miss). Showing the first 100 of " +
             count(uint64_t(num(a, {"totals", "misses"}) + num(a, {"totals", "crack_misses"}))) +
             ".</p><div class=\"scroll\"><table><tr><th class=\"n\">from</th>"
             "<th class=\"n\">to</th><th>player eye</th><th>eye</th><th>direction</th><th class=\"n\">eye leaf</th><th class=\"n\">leaf</th>"
             "<th class=\"n\">enter</th><th class=\"n\">exit</th><th>stopped by</th><th class=\"n\">at</th><th class=\"n\">rays"
             "</th><th class=\"n\">PVS byte</th><th class=\"n\">bit</th><th class=\"n\">byte value</th></tr>";
        size_t n = 0;
        for (const Json &m : *ms) {
            if (n++ >= 100) break;
            const Json *d = at(m, {"direction"});
            std::string dir = "—";
            if (d && d->is_array() && d->size() == 3 && (*d)[0].is_number())
                dir = fmt("(%.3f, ", (*d)[0].get<double>()) + fmt("%.3f, ", (*d)[1].get<double>()) + fmt("%.3f)", (*d)[2].get<double>());
            o += "<tr><td class=\"n\">" + fmt("%.0f", num(m, {"from"})) + "</td><td class=\"n\">" + fmt("%.0f", num(m, {"to"})) +
                 "</td><td>" + (isTrueAt(m, "player_eye") ? "yes" : "<span class=\"muted\">no</span>") + "</td><td>" +
                 jpos(at(m, {"eye"})) + "</td><td>" + dir + "</td><td class=\"n\">" +
                 fmt("%.0f", num(m, {"eye_leaf"})) + "</td><td class=\"n\">" + fmt("%.0f", num(m, {"leaf"})) +
                 "</td><td class=\"n\">" + fmt("%.1f", num(m, {"enter"})) + "</td><td class=\"n\">" + fmt("%.1f", num(m, {"exit"})) +
                 "</td><td>" + htmlEscape(text(m, {"stopped_by"})) + "</td><td class=\"n\">" + fmt("%.1f", num(m, {"stop"})) +
                 "</td><td class=\"n\">" + fmt("%.0f", num(m, {"rays"})) + "</td><td class=\"n\">" +
                 fmt("%.0f", num(m, {"pvs_byte"})) + "</td><td class=\"n\">" + fmt("%.0f", num(m, {"pvs_bit"})) +
                 "</td><td class=\"n\">" + hexByte(int(num(m, {"pvs_byte_value"}))) + "</td></tr>";
        }
        o += "</table></div>";
    }
    return o;
}

}  // namespace

std::string pvsAuditHtml(const Json &a, const std::string &dir) {
    std::string o;
    const std::string map = text(a, {"map"});
    const double misses = num(a, {"totals", "misses"}), slack = num(a, {"totals", "slack_share"});
    // The same head as report.html: nothing may load from elsewhere.
    o += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
         "<meta name=\"color-scheme\" content=\"light dark\">"
         "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; img-src 'self' file: data:; "
         "style-src 'unsafe-inline'\">"
         "<title>visaudit PVS audit: " + htmlEscape(map) + "</title><style>" + std::string(html_assets::kCss) +
         "</style></head><body>\n";
    o += "<header><h1>PVS audit: " + htmlEscape(map) + "</h1><p class=\"meta\">visaudit " +
         htmlEscape(text(a, {"tool", "version"})) + " · " + htmlEscape(text(a, {"format"})) + "</p>";
    o += std::string("<p class=\"verdict ") + (misses > 0 ? "bad" : "good") + "\"><b>" + count(uint64_t(misses)) +
         " misses</b> (cluster pairs a player's eye sees although the PVS says hidden; best 0) · <b>" + percent(slack) +
         " slack</b> (PVS-visible pairs no eye point saw)" +
         (num(a, {"totals", "crack_misses"}) > 0
              ? " · " + count(uint64_t(num(a, {"totals", "crack_misses"}))) + " crack misses (seen only where no player fits)"
              : std::string()) +
         "</p></header>\n";
    o += pvsTotalsSection(a);
    o += pvsImageSection(a, dir);
    o += pvsHistogramSection(a);
    o += pvsWorstSection(a);
    o += pvsMissesSection(a);
    o += "</section>\n<p class=\"muted\">How to read every number: docs/pvs-audit.md in visaudit's sources.</p></body></html>\n";
    return o;
}

bool writePvsAudit(const PvsAuditResult &r, const std::string &dir, Json *json, std::string *err) {
    std::vector<uint8_t> rgb;
    int w = 0, h = 0;
    std::string image;
    if (pvsAuditImage(r, &rgb, &w, &h)) {
        image = kImageName;
        if (!writePngRgb8(dir + "/" + image, w, h, rgb.data(), err)) return false;
    }
    *json = pvsAuditJson(r, image);
    return writeFileAtomic(dir + "/pvs-audit.json", json->dump(2) + "\n", err) &&
           writeFileAtomic(dir + "/pvs-audit.html", pvsAuditHtml(*json, dir), err);
}

}  // namespace va
