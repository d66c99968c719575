// The report model (reports/report_model.h): every key table against docs/report-schema.json, so the
// result structs, report.json and the schema cannot drift apart; and a table's write and read are
// each other's inverse.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "reports/report_model.h"

namespace va {
namespace {

using Json = nlohmann::ordered_json;

Json loadSchema() {
    std::ifstream f(std::string(VISAUDIT_SOURCE_DIR) + "/docs/report-schema.json");
    EXPECT_TRUE(f.good()) << "cannot open docs/report-schema.json";
    return Json::parse(f);
}

// The schema of the object at `path`: steps are property names, "[]" (array items), "*" (the
// additionalProperties schema of a map) and "#name" (a $defs entry); $ref is followed.
const Json *schemaAt(const Json &root, const std::string &path) {
    const Json *s = &root;
    auto deref = [&](const Json *x) {
        while (x && x->contains("$ref")) {
            const std::string ref = (*x)["$ref"];  // "#/$defs/NAME"
            x = &root["$defs"][ref.substr(ref.rfind('/') + 1)];
        }
        return x;
    };
    std::stringstream in(path);
    std::string step;
    while (s && std::getline(in, step, '/')) {
        s = deref(s);
        if (step[0] == '#') s = &root["$defs"][step.substr(1)];
        else if (step == "[]") s = s->contains("items") ? &(*s)["items"] : nullptr;
        else if (step == "*") s = s->contains("additionalProperties") ? &(*s)["additionalProperties"] : nullptr;
        else if (s->contains("properties") && (*s)["properties"].contains(step)) s = &(*s)["properties"][step];
        else s = nullptr;
    }
    return deref(s);
}

std::set<std::string> propertiesOf(const Json *s) {
    std::set<std::string> keys;
    if (s && s->contains("properties"))
        for (auto it = (*s)["properties"].begin(); it != (*s)["properties"].end(); ++it) keys.insert(it.key());
    return keys;
}

// Every key of the table is a property of the schema's object at `path`; with `exact`, the object
// has no property the table does not write but those in `others` (keys its writer adds: "ran",
// "reason", a note).
template <class Table>
void expectTableMatchesSchema(const Table &table, const std::string &path, bool exact,
                              std::set<std::string> others = {}) {
    static const Json schema = loadSchema();
    const Json *s = schemaAt(schema, path);
    ASSERT_NE(s, nullptr) << "no schema object at " << path;
    const std::set<std::string> props = propertiesOf(s);
    std::set<std::string> written;
    for (const std::string &k : json::keyNames(table)) {
        EXPECT_TRUE(props.count(k)) << path << ": the table writes '" << k << "', which the schema does not describe";
        EXPECT_TRUE(written.insert(k).second) << path << ": key '" << k << "' twice in the table";
    }
    if (!exact) return;
    for (const std::string &p : props)
        EXPECT_TRUE(written.count(p) || others.count(p))
            << path << ": the schema describes '" << p << "', which no table writes";
}

TEST(ReportModel, EveryTableMatchesTheSchema) {
    using json::kKeys;
    // The funnel row's own counts share one schema object (the union over stages).
    expectTableMatchesSchema(kKeys<FrustumStats>, "#stage", false);
    expectTableMatchesSchema(kKeys<BackfaceStats>, "#stage", false);
    expectTableMatchesSchema(kKeys<ClipStats>, "#stage", false);
    expectTableMatchesSchema(json::kZBufferStageKeys, "#stage", false);
    expectTableMatchesSchema(kKeys<CellsStats>, "#stage", false);
    expectTableMatchesSchema(kKeys<PortalStats>, "#stage", false);
    expectTableMatchesSchema(kKeys<GridStats>, "#stage", false);
    expectTableMatchesSchema(kKeys<OcclusionStats>, "#stage", false);
    expectTableMatchesSchema(kKeys<RaycastStats>, "#stage", false);

    expectTableMatchesSchema(kKeys<ZBufferStats>, "#view/zbuffer", true);
    expectTableMatchesSchema(kKeys<DetailResult>, "#view/detail", true, {"reason"});
    expectTableMatchesSchema(kKeys<DetailObject>, "#view/detail/flagged/[]", true);
    expectTableMatchesSchema(kKeys<OrderingRow>, "#view/ordering/table/[]", true);
    expectTableMatchesSchema(kKeys<PainterResult>, "#view/ordering/painter", true);
    expectTableMatchesSchema(kKeys<OverlapTests>, "#view/ordering/painter/overlaps", true);
    expectTableMatchesSchema(kKeys<BspViewResult>, "#view/ordering/bsp", true);
    expectTableMatchesSchema(kKeys<DrawStats>, "#view/ordering/bsp/back_to_front", true);
    expectTableMatchesSchema(kKeys<DrawStats>, "#view/ordering/overdraw_by_order/[]", true, {"order"});
    expectTableMatchesSchema(kKeys<ABufferResult>, "#view/ordering/abuffer", true, {"reason"});
    expectTableMatchesSchema(kKeys<CrossCheck>, "#view/raycast/cross_check", true);
    expectTableMatchesSchema(kKeys<CrossCheck::Example>, "#view/raycast/cross_check/genuine_examples/[]", true);
    expectTableMatchesSchema(kKeys<EffectsStats>, "#view/raycast/effects", true);
    expectTableMatchesSchema(kKeys<LightShadowStats>, "#view/raycast/lights/[]", true);
    expectTableMatchesSchema(kKeys<ReferenceVisibility>, "#view/audit/reference", true);
    expectTableMatchesSchema(kKeys<StageCullAudit>, "#view/audit/false_culls/by_stage/*", true);
    expectTableMatchesSchema(kKeys<FalseCullOffender>, "#view/audit/false_culls/by_stage/*/worst/[]", true);
    expectTableMatchesSchema(kKeys<ZFightFormatStats>, "#view/depth/formats/*", true);
    expectTableMatchesSchema(kKeys<BspStats>, "bsp_tree", true, {"reason"});
}

// A table writes what it reads back: every member survives the round trip (doubles bit for bit,
// NaN as null and back as NaN), derived keys are written and skipped on reading.
TEST(ReportModel, WriteThenReadIsTheIdentity) {
    OcclusionStats o;
    o.occludersUsed = 7;
    o.objectsCulled = 1ull << 40;
    o.prepassMs = 0.1 + 0.2;
    o.testMs = std::nan("");
    const Json j = json::write(o);
    EXPECT_TRUE(j["test_ms"].is_null());
    const OcclusionStats back = json::read<OcclusionStats>(j);
    EXPECT_EQ(back.occludersUsed, 7u);
    EXPECT_EQ(back.objectsCulled, 1ull << 40);
    EXPECT_EQ(back.prepassMs, 0.1 + 0.2);
    EXPECT_TRUE(std::isnan(back.testMs));

    DetailResult d;
    d.objectsDrawn = 3;
    d.flagged.resize(2);
    d.flagged[1].name = "crate";
    d.flagged[1].projectedPixels = 1.5;
    d.flagged[1].tooSmall = true;
    const Json dj = json::write(d);
    EXPECT_EQ(dj["ran"], true);
    EXPECT_EQ(dj.dump(), json::write(json::read<DetailResult>(dj)).dump());

    GridStats g;
    g.dims[0] = 4, g.dims[1] = 5, g.dims[2] = 6;
    EXPECT_EQ(json::write(g)["dims"].dump(), "[4,5,6]");
    EXPECT_EQ(json::read<GridStats>(json::write(g)).dims[2], 6);

    // A value of another type leaves the member as it was.
    Json bad = json::write(o);
    bad["occluders_used"] = "seven";
    EXPECT_EQ(json::read<OcclusionStats>(bad).occludersUsed, 0u);
}

}  // namespace
}  // namespace va
