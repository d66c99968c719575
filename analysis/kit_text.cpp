// The texts of an assignment kit (kit_text.h).
#include "analysis/kit_text.h"

#include <cstdio>
#include <set>

namespace va::kit {

namespace {

std::string g17(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

bool has(const KitSettings &ks, Stage s) { return std::find(ks.stages.begin(), ks.stages.end(), s) != ks.stages.end(); }

}  // namespace

std::string sceneObj(const Scene &scene, const std::string &label) {
    std::string o = "# visaudit assignment kit: the scene " + label + "\n"
                    "# World coordinates. The k-th face line (\"f\") is triangle id k (ids count from 0);\n"
                    "# every triangle has its own three vertex lines. Objects (\"o\") are the scene's source objects.\n";
    size_t nextVertex = 1;
    for (const SourceObject &src : scene.sources) {
        const Material &m = scene.materials[src.material];
        o += "o " + (src.name.empty() ? std::string("object") : src.name) + "\n# material " + m.name +
             (m.doubleSided ? " (double-sided: never backface-culled)" : " (single-sided)") + "\n";
        for (uint32_t t = src.firstTriangle; t < src.firstTriangle + src.triangleCount; ++t) {
            if (scene.triangleObject[t] == kExcludedTriangle)
                o += "# triangle " + std::to_string(t) + " is excluded (zero area or a non-finite corner)\n";
            for (int k = 0; k < 3; ++k) {
                const Vec3 p = scene.positions[scene.indices[3 * size_t(t) + size_t(k)]];
                o += "v " + g17(p.x) + " " + g17(p.y) + " " + g17(p.z) + "\n";
            }
            o += "f " + std::to_string(nextVertex) + " " + std::to_string(nextVertex + 1) + " " +
                 std::to_string(nextVertex + 2) + "\n";
            nextVertex += 3;
        }
    }
    return o;
}

std::string kitReadme(const nlohmann::ordered_json &a, const KitSettings &ks) {
    std::string o;
    o += "# Visibility assignment\n\n";
    o += "This kit was made by `visaudit assignment` from the scene `" + a["scene"]["source"].get<std::string>() +
         "` (" + std::to_string(a["scene"]["triangles"].get<uint64_t>()) + " triangles). For each view below you "
         "implement the stages listed, each on **its own input file**: every stage's input is what the "
         "reference implementation's previous stage produced, so a mistake in one stage never costs you "
         "marks in the next.\n\n";
    o += "Read `CONVENTIONS.md` first: every count and image is graded against those rules exactly.\n\n";
    o += "## Files\n\n";
    o += "| file | what |\n|---|---|\n";
    o += "| `assignment.json` | the stages, the views with every camera number, and each view's input files |\n";
    o += "| `CONVENTIONS.md` | camera, clip space, pixel centres, fill rule, depth formats, tie rule |\n";
    o += "| `scene.obj` | the scene in world coordinates; the k-th face is triangle id k |\n";
    o += "| `views.json` | the views (the same numbers as `assignment.json`) |\n";
    o += "| `views/VIEW/STAGE.json` | a stage's input for one view |\n";
    o += "| `template/submission.json` | what you hand in: fill in every `null` and list |\n\n";
    o += "Views:\n\n| view | folder | size | projection | depth format |\n|---|---|---|---|---|\n";
    for (const auto &v : a["views"])
        o += "| " + v["name"].get<std::string>() + " | `views/" + v["dir"].get<std::string>() + "` | " +
             std::to_string(v["width"].get<int>()) + " × " + std::to_string(v["height"].get<int>()) + " | " +
             (v.contains("ortho_height") ? "orthographic" : "perspective") + " | `" + v["depth_format"].get<std::string>() +
             "` |\n";
    o += "\nEvery input file is JSON with a `format` key, a header (the view, the numbers the stage needs) and a "
         "`triangles` array, one triangle per line. Numbers are written so that they read back as exactly the "
         "same double. In Python:\n\n";
    o += "```python\nimport json\nkit = json.load(open(\"views/" + a["views"][0]["dir"].get<std::string>() +
         "/" + stageName(ks.stages.front()) + ".json\"))\nfor t in kit[\"triangles\"]:\n    print(t[\"id\"], t)\n```\n\n";

    o += "## The stages\n\n";
    if (has(ks, Stage::backface)) {
        o += "### backface (`views/VIEW/backface.json`)\n\n";
        o += "Input: `eye`, `forward` (the view direction) and `projection`; `triangles`: `id`, `double_sided`, "
             "`v` (three world-space corners). These are the triangles of the objects the coarse stages "
             "(cells or grid, frustum, occlusion) kept, in submission order.\n\n";
        o += "Hand in: `triangles_in`, `triangles_tested` (single-sided triangles whose plane you evaluated), "
             "`triangles_culled`, `double_sided_exempt`, `edge_on` (culled because the eye lies exactly in the "
             "plane), `triangles_out`, and `kept`: the ids you keep (any order).\n\n";
    }
    if (has(ks, Stage::clip)) {
        o += "### clip (`views/VIEW/clip.json`)\n\n";
        o += "Input: `width`, `height`, `near`, `far`, `sx`, `sy`, `guard_band_px`; `triangles`: `id`, `v` (three "
             "corners in **view space**). A corner (x, y, z) is (sx·x, sy·y, w, d) in clip space with d = −z and "
             "w = d (perspective) or 1 (orthographic).\n\n";
        o += "Hand in: `triangles_in`, `trivially_rejected`, `inside`, `guard_band_accepted`, `clipped`, "
             "`clipped_away`, `edge_on`, `per_plane` (triangles clipped against each plane), `polygon_vertices` "
             "(clipped polygons by vertex count), `triangles_out` (screen triangles after fan triangulation), and "
             "`polygons`: for every triangle that reaches the rasterizer, `{\"id\": ID, \"vertices\": [[x, y, w, d], "
             "...]}` in clip space (an accepted triangle: its three corners; a clipped one: the polygon "
             "Sutherland–Hodgman leaves). Polygons are matched with the tolerance the instructor sets; a polygon "
             "may start at any of its vertices, but its orientation must be kept.\n\n";
    }
    if (has(ks, Stage::zbuffer)) {
        o += "### zbuffer (`views/VIEW/zbuffer.json`)\n\n";
        o += "Input: `width`, `height`, `near`, `far`, `depth_format` (with its formula `depth_stored` and "
             "`nearer_is`), `subpixel_bits`; `triangles` in draw order: `id`, `xy` (x0, y0, x1, y1, x2, y2 in "
             "fixed point: pixels × 256, y down), `plane` (a, b, c: the depth plane, see CONVENTIONS.md).\n\n";
        o += "Hand in: `triangles_in`, `triangles_drawn`, `triangles_empty`, `fragments`, `depth_passes`, "
             "`out_of_range_fragments`, `covered_pixels`, `overdraw`, `depth_complexity`, "
             "`max_depth_complexity`, `histogram`, and per-pixel images named by";
        for (size_t i = 0; i < ks.images.size(); ++i) o += std::string(i ? " and" : "") + " `" + ks.images[i] + "`";
        o += " (file names relative to your submission folder):\n\n";
        o += "- `ids`: 1 + the id of the visible triangle, 0 for background; a 16-bit grayscale PNG (ids below "
             "65535), a one-channel EXR or PFM (float values, exact below 2^24), or a CSV file;\n";
        o += "- `depth`: the view depth d of the visible fragment (not the stored format value), +inf or 0 for "
             "background; an EXR or PFM (32-bit float), or a CSV file.\n\n";
        o += "A CSV image has `height` lines of `width` comma-separated numbers, the top row first. The grader "
             "compares every pixel with the reference and tells a fill-rule difference (a pixel centre on an "
             "edge) from a depth-test difference.\n\n";
    }
    if (has(ks, Stage::painter)) {
        o += "### painter (`views/VIEW/painter.json`)\n\n";
        o += "Input: `width`, `height`, `key` (the sort key to use); `triangles` (every triangle that reaches the "
             "screen, no culling): `id`, `depths` (the view depths of its three unclipped corners), "
             "`single_sided`, `plane`, `screen` (its screen triangles in fixed point, as the z-buffer's).\n\n";
        o += "Hand in: `triangles_drawn`, `fragments`, `covered_pixels`, `overdraw` (fragments / covered pixels), "
             "`order` (the ids back to front, the order you draw them) and `ids`, the picture (1 + id per pixel, "
             "0 background; the same image formats as the z-buffer's).\n\n";
    }
    o += "## Handing in\n\n";
    o += "Copy `template/submission.json` into a folder of your own, fill in every value, put your images next "
         "to it, and hand in the folder. Keys you leave `null` (or leave out) are graded as missing. The grade "
         "page (`grade.html`) shows per view and stage what passed, what failed with both values, the "
         "difference images, and a hint where the pattern of a mistake is recognisable.\n";
    return o;
}

std::string kitConventions(const KitSettings &ks, const std::vector<DepthFormatSpec> &formats) {
    std::string o;
    o += "# Conventions\n\n";
    o += "These are visaudit's conventions (its docs/conventions.md and docs/rasterizer.md); the reference "
         "answers follow them exactly.\n\n";
    o += "## Camera and spaces\n\n";
    o += "- World: right-handed. View space: the camera looks down −z, +y up, +x right. View depth d = −z_view > 0.\n";
    o += "- Clip space (Direct3D-style depth range): x_c = sx·x_view, y_c = sy·y_view, w = d (perspective) or 1 "
         "(orthographic); the view frustum is −w ≤ x_c ≤ w, −w ≤ y_c ≤ w, near ≤ d ≤ far. sx = 1/(tan(fov_y/2)·aspect), "
         "sy = 1/tan(fov_y/2) (orthographic: 2/(ortho_height·aspect), 2/ortho_height); aspect = width/height.\n";
    o += "- Raster: x_n = x_c/w, y_n = y_c/w; pixel coordinates px = (x_n + 1)·W/2, py = (1 − y_n)·H/2. Pixel (0, 0) "
         "is the top-left one, and pixel (x, y) is sampled at its centre (x + 0.5, y + 0.5).\n";
    o += "- Screen triangles are in fixed point with 8 sub-pixel bits: X = px·256 rounded to the nearest integer, "
         "ties to even.\n\n";
    o += "## backface\n\n";
    o += "- Front faces are counter-clockwise seen from the front. The plane of (v0, v1, v2) is n·p + k = 0 with "
         "n = (v1 − v0) × (v2 − v0) and k = −n·v0.\n";
    o += "- Perspective: a triangle is front-facing when n·eye + k > 0. Exactly 0 (the eye in the plane) is "
         "*edge-on*: it covers no area and is culled (counted in `edge_on` and in `triangles_culled`). The sign is "
         "decided exactly (the reference uses exact predicates where double rounding could flip it).\n";
    o += "- Orthographic: front-facing when s = n·(−forward) > −err, err = γ(4)·(|n.x·f.x| + |n.y·f.y| + |n.z·f.z|) "
         "with f = forward and γ(4) = 4u/(1 − 4u), u = 2^−53: where the sign is within the rounding of the dot product "
         "the triangle is kept (conservative). A culled triangle with s exactly 0 is counted in `edge_on`.\n";
    o += "- Double-sided triangles are never tested (`double_sided_exempt`) and always kept.\n\n";
    o += "## clip\n\n";
    o += "- Outcodes per corner: near d < near, far d > far, left x_c < −w, right x_c > w, bottom y_c < −w, top "
         "y_c > w. **Trivial reject**: all three corners outside the same one of these planes.\n";
    o += "- **Edge-on**: the triangle's plane passes through the eye (perspective) or contains the view direction "
         "(orthographic): it covers no area and is dropped (`edge_on`).\n";
    o += "- **Guard band** of G = " + g17(ks.clip.guardBandPixels) + " pixels: gx = 1 + G/(W/2), gy = 1 + G/(H/2). "
         "A triangle whose corners are all inside near, far and the guard band (−gx·w ≤ x_c ≤ gx·w, −gy·w ≤ y_c ≤ gy·w) "
         "is accepted whole: `inside` when every corner is inside the view frustum, else `guard_band_accepted` (the "
         "rasterizer's pixel box clips it).\n";
    o += "- Otherwise it is **clipped**: Sutherland–Hodgman in clip space, before the divide, against these planes "
         "in this order, each only when a corner is outside it: near (d − near ≥ 0 inside), far (far − d ≥ 0), "
         "guard-band left (x + gx·w ≥ 0), right (gx·w − x ≥ 0), bottom (y + gy·w ≥ 0), top (gy·w − y ≥ 0). The near "
         "plane is always clipped when a corner is behind it, so nothing behind the eye is ever projected. "
         "`per_plane` counts the triangles clipped against each plane; the sides are the guard band's, never "
         "the viewport's.\n";
    o += "- One plane: walk the polygon's edges a → b from its first vertex; emit a when a is inside; when a and b "
         "are on different sides, emit the intersection computed from the inside vertex p towards the outside "
         "one q: t = dp / (dp − dq), p + t·(q − p) on all four of x, y, w, d (dp ≥ 0 > dq their plane values).\n";
    o += "- Fewer than 3 vertices left: `clipped_away`. Otherwise `polygon_vertices[n]` counts it and the fan "
         "(v0, v(k−1), v(k)), k = 2 … n−1, gives n − 2 screen triangles (`triangles_out` counts every screen "
         "triangle, accepted ones included).\n\n";
    o += "## zbuffer\n\n";
    o += "- Triangles are drawn in the input's order (submission order).\n";
    o += "- Coverage, in 64-bit integers on the fixed-point corners: twice the signed area "
         "A = (x1 − x0)(y2 − y0) − (y1 − y0)(x2 − x0); A = 0 draws nothing; A < 0 (counter-clockwise as the viewer sees "
         "it) swaps v1 and v2. For the edges v1→v2, v2→v0, v0→v1 of the (swapped) triangle, with dx, dy the edge's "
         "vector from a to b, E(p) = dx·(p.y − a.y) − dy·(p.x − a.x) at the centre p = (256x + 128, 256y + 128). "
         "The centre is covered when every E > 0, or E = 0 on a **top-left** edge: a left edge (dy < 0) or a top edge "
         "(dy = 0 and dx > 0). Two triangles sharing an edge never both cover a centre, and a closed mesh has no "
         "cracks. Both windings are drawn (culling is the backface stage's job).\n";
    o += "- Depth, per covered centre (px, py) = (x + 0.5, y + 0.5), in double from the triangle's plane: "
         "perspective d = 1 / ((a·px + b·py) + c), orthographic d = (a·px + b·py) + c, evaluated in exactly that "
         "order (no fused multiply-add).\n";
    o += "- The depth format maps d to the stored value with its own arithmetic; depths it cannot represent are "
         "clamped to the nearest representable value and counted (`out_of_range_fragments`). Formats in this "
         "kit:\n\n";
    o += "  | format | stored value (d: view depth; n, f: near, far) | nearer is |\n  |---|---|---|\n";
    for (const DepthFormatSpec &f : formats) {
        const DepthFormatInfo &info = depthFormatInfo(f.format);
        o += "  | `" + depthFormatName(f) + "` | `" + info.stored + "` | " + (info.nearerIsLarger ? "larger" : "smaller") +
             " |\n";
    }
    o += "\n  Each view's zbuffer.json repeats its own (`depth_format`, `depth_stored`, `nearer_is`).\n\n";
    o += "- **Depth test**: a fragment passes when its stored value is nearer than the stored one (LESS; GREATER "
         "on the raw value for formats where nearer is larger). At **equal stored values the first drawn fragment "
         "wins**, as on hardware. The buffer starts empty (every pixel farther than anything).\n";
    o += "- Counts: `triangles_drawn` (covered at least one centre), `triangles_empty` (none: zero area, "
         "sub-pixel, off screen), `fragments` (covered centres over all triangles), `depth_passes`, "
         "`covered_pixels` (pixels with a fragment), `overdraw` = depth_passes / covered_pixels, "
         "`depth_complexity` = fragments / covered_pixels, `max_depth_complexity` (most fragments at one pixel), "
         "`histogram[k]` = pixels with exactly k fragments (`[0]`: uncovered pixels; up to the maximum).\n\n";
    o += "## painter\n\n";
    o += "- The sort key of a triangle from the view depths d0, d1, d2 of its three (unclipped) corners: "
         "`centroid` (d0 + d1 + d2) / 3, `nearest_vertex` the least, `farthest_vertex` the greatest. Draw the "
         "largest key first (back to front); equal keys: the larger id first, so the lower id shows.\n";
    o += "- Draw each triangle's screen triangles with the z-buffer's coverage and no depth test: every fragment "
         "overwrites the pixel. A single-sided triangle whose screen winding is the back one (A > 0 above) is not "
         "drawn.\n";
    o += "- Counts: `triangles_drawn` (the triangles in your order), `fragments` (fragments written), "
         "`covered_pixels`, `overdraw` = fragments / covered_pixels.\n\n";
    o += "## Ids and images\n\n";
    o += "- A triangle's id is its index in the scene's source order (the k-th face of scene.obj).\n";
    o += "- Per-pixel images are `width` × `height`, the top row first: ids hold 1 + id (0 background); depths "
         "hold the view depth d (+inf or 0 background).\n";
    return o;
}

}  // namespace va::kit
