// The report's keys, declared once per result struct (common/json_fields.h): report.json is written
// from these tables (reports/report_json.cpp), the readers that need a section back as a struct use
// the same tables (json::read), and tests/test_report.cpp checks every table against
// docs/report-schema.json, so the struct, the file and the schema cannot drift apart. A key's
// meaning and best value are the member's comment in its struct and the schema's description.
#pragma once

#include <tuple>

#include "analysis/results.h"
#include "common/json_fields.h"

namespace va::json {

// A count of "none" (0) written as null, e.g. a nearest distance where nothing was found.
inline OJson positiveOrNull(double v) { return v > 0 ? value(v) : OJson(nullptr); }

// ---- The stage funnel's own counts (view.stages[], when the stage ran) --------------------------

template <> inline constexpr auto kKeys<FrustumStats> = std::tuple{
    key("objects_in", &FrustumStats::objectsIn),
    key("objects_culled", &FrustumStats::objectsCulled),
    key("objects_inside", &FrustumStats::objectsInside),
    key("objects_intersecting", &FrustumStats::objectsIntersecting),
    key("nodes_visited", &FrustumStats::nodesVisited),
    key("plane_tests", &FrustumStats::planeTests),
    key("plane_tests_brute_force", &FrustumStats::planeTestsBruteForce)};

// trianglesCulled is the funnel row's triangles_culled (same count): not repeated.
template <> inline constexpr auto kKeys<BackfaceStats> = std::tuple{
    key("triangles_tested", &BackfaceStats::trianglesTested),
    key("double_sided_exempt", &BackfaceStats::doubleSidedExempt),
    key("edge_on", &BackfaceStats::edgeOn)};

// The z-buffer's funnel row (its triangles in/out are the row's own).
inline constexpr auto kZBufferStageKeys = std::tuple{
    key("triangles_drawn", &ZBufferStats::trianglesDrawn),
    key("triangles_empty", &ZBufferStats::trianglesEmpty),
    key("fragments", &ZBufferStats::fragments),
    key("depth_passes", &ZBufferStats::depthPasses),
    key("out_of_range_fragments", &ZBufferStats::outOfRangeFragments)};

// view.zbuffer: what the z-buffer drew, per pixel.
template <> inline constexpr auto kKeys<ZBufferStats> = std::tuple{
    key("covered_pixels", &ZBufferStats::coveredPixels),
    key("fragments", &ZBufferStats::fragments),
    key("depth_passes", &ZBufferStats::depthPasses),
    key("overdraw", &ZBufferStats::overdraw),
    key("depth_complexity", &ZBufferStats::depthComplexity),
    key("max_depth_complexity", &ZBufferStats::maxDepthComplexity),
    key("histogram", &ZBufferStats::histogram)};

// The cells stage with a map's PVS (the row adds the view's cells note).
template <> inline constexpr auto kKeys<CellsStats> = std::tuple{
    key("camera_leaf", &CellsStats::cameraLeaf),
    key("camera_cluster", &CellsStats::cameraCluster),
    key("camera_in_void", &CellsStats::cameraInVoid),
    key("clusters_visible", &CellsStats::clustersVisible),
    key("clusters_total", &CellsStats::clustersTotal),
    key("objects_in", &CellsStats::objectsIn),
    key("objects_culled", &CellsStats::objectsCulled),
    key("objects_no_cluster", &CellsStats::objectsNoCluster)};

// The cells stage through the scene's portals (the row adds the view's cells note).
template <> inline constexpr auto kKeys<PortalStats> = std::tuple{
    key("camera_cell", &PortalStats::cameraCell),
    key("camera_cells", &PortalStats::cameraCells),
    key("camera_outside", &PortalStats::cameraOutside),
    key("cells_visible", &PortalStats::cellsVisible),
    key("cells_total", &PortalStats::cellsTotal),
    key("cells_visited", &PortalStats::cellsVisited),
    key("portals_tested", &PortalStats::portalsTested),
    key("portals_passed", &PortalStats::portalsPassed),
    key("portals_edge_on", &PortalStats::portalsEdgeOn),
    key("portals_in_portal", &PortalStats::portalsInPortal),
    key("depth_limit_hits", &PortalStats::depthLimitHits),
    key("budget_exceeded", &PortalStats::budgetExceeded),
    key("objects_in", &PortalStats::objectsIn),
    key("objects_culled", &PortalStats::objectsCulled),
    key("objects_no_cell", &PortalStats::objectsNoCell)};

template <> inline constexpr auto kKeys<GridStats> = std::tuple{
    key("dims", &GridStats::dims),
    key("cell_size", &GridStats::cellSize),
    key("cells_total", &GridStats::cellsTotal),
    key("registrations", &GridStats::registrations),
    key("cells_skipped", &GridStats::cellsSkipped),
    key("cells_empty", &GridStats::cellsEmpty),
    key("cells_tested", &GridStats::cellsTested),
    key("cells_visible", &GridStats::cellsVisible),
    key("plane_tests", &GridStats::planeTests),
    key("objects_in", &GridStats::objectsIn),
    key("objects_culled", &GridStats::objectsCulled)};

template <> inline constexpr auto kKeys<OcclusionStats> = std::tuple{
    key("occluders_used", &OcclusionStats::occludersUsed),
    key("occluder_triangles", &OcclusionStats::occluderTriangles),
    key("prepass_fragments", &OcclusionStats::prepassFragments),
    key("prepass_pixels", &OcclusionStats::prepassPixels),
    key("hiz_levels", &OcclusionStats::hizLevels),
    key("objects_in", &OcclusionStats::objectsIn),
    key("objects_tested", &OcclusionStats::objectsTested),
    key("objects_culled", &OcclusionStats::objectsCulled),
    key("objects_hidden", &OcclusionStats::objectsHidden),
    key("objects_no_pixel", &OcclusionStats::objectsNoPixel),
    key("objects_near_plane", &OcclusionStats::objectsNearPlane),
    key("texels_read", &OcclusionStats::texelsRead),
    key("prepass_ms", &OcclusionStats::prepassMs),
    key("test_ms", &OcclusionStats::testMs)};

// ClipStats::trianglesIn / trianglesOut are the funnel row's triangles_in / triangles_out.
template <> inline constexpr auto kKeys<ClipStats> = std::tuple{
    key("trivially_rejected", &ClipStats::trivialRejected),
    key("inside", &ClipStats::inside),
    key("guard_band_accepted", &ClipStats::guardBandAccepted),
    key("clipped", &ClipStats::clipped),
    key("clipped_away", &ClipStats::clippedAway),
    key("edge_on", &ClipStats::edgeOn),
    derived<ClipStats>("per_plane",
                       [](const ClipStats &c) {
                           OJson planes;
                           for (int p = 0; p < kClipPlaneCount; ++p) planes[kClipPlaneNames[p]] = c.perPlane[size_t(p)];
                           return planes;
                       }),
    // Every key "3" .. "8" and "9+" is always present (zeros included), so graders and diffs see a
    // fixed shape. Indices 0..2 cannot hold a polygon (clipped-away triangles are clipped_away).
    derived<ClipStats>("polygon_vertices", [](const ClipStats &c) {
        OJson poly;
        for (int k = 3; k <= 9; ++k) poly[k == 9 ? std::string("9+") : std::to_string(k)] = c.polygonVertices[size_t(k)];
        return poly;
    })};

template <> inline constexpr auto kKeys<RaycastStats> = std::tuple{
    key("rays", &RaycastStats::rays),
    key("hits", &RaycastStats::hits),
    key("packets", &RaycastStats::packets)};

// ---- The detail audit (view.detail) -------------------------------------------------------------

template <> inline constexpr auto kKeys<DetailObject> = std::tuple{
    key("object", &DetailObject::object),
    key("name", &DetailObject::name),
    key("triangles_drawn", &DetailObject::trianglesDrawn),
    key("triangles_no_center", &DetailObject::trianglesNoCenter),
    key("fragments", &DetailObject::fragments),
    key("pixels_visible", &DetailObject::pixelsVisible),
    key("projected_pixels", &DetailObject::projectedPixels),
    key("too_small", &DetailObject::tooSmall),
    key("over_detailed", &DetailObject::overDetailed),
    key("triangles_saved", &DetailObject::trianglesSaved)};

template <> inline constexpr auto kKeys<DetailResult> = std::tuple{
    derived<DetailResult>("ran", [](const DetailResult &) { return OJson(true); }),
    key("objects_drawn", &DetailResult::objectsDrawn),
    key("triangles_drawn", &DetailResult::trianglesDrawn),
    key("triangles_no_center", &DetailResult::trianglesNoCenter),
    key("pixels_visible", &DetailResult::pixelsVisible),
    key("triangles_per_visible_pixel", &DetailResult::trianglesPerVisiblePixel),
    key("objects_too_small", &DetailResult::objectsTooSmall),
    key("objects_over_detailed", &DetailResult::objectsOverDetailed),
    key("triangles_savable", &DetailResult::trianglesSavable),
    key("flagged", &DetailResult::flagged),
    key("ms", &DetailResult::ms)};

// ---- The ordering audit (view.ordering) ---------------------------------------------------------

template <> inline constexpr auto kKeys<DrawStats> = std::tuple{
    key("fragments", &DrawStats::fragments),
    key("depth_passes", &DrawStats::depthPasses),
    key("covered_pixels", &DrawStats::coveredPixels),
    key("overdraw", &DrawStats::overdraw),
    key("depth_complexity", &DrawStats::depthComplexity),
    key("ms", &DrawStats::ms)};

template <> inline constexpr auto kKeys<OrderingRow> = std::tuple{
    key("method", &OrderingRow::method),
    key("build_ms", &OrderingRow::buildMs),
    key("draw_ms", &OrderingRow::drawMs),
    key("wrong_pixels", &OrderingRow::wrongPixels),
    key("tie_pixels", &OrderingRow::tiePixels),
    key("edge_pixels", &OrderingRow::edgePixels),
    key("overdraw", &OrderingRow::overdraw),
    key("memory_bytes", &OrderingRow::memoryBytes)};

template <> inline constexpr auto kKeys<OverlapTests> = std::tuple{
    key("pairs", &OverlapTests::pairs),
    key("bounds_disjoint", &OverlapTests::boundsDisjoint),
    key("behind_plane", &OverlapTests::behindPlane),
    key("in_front_of_plane", &OverlapTests::inFrontOfPlane),
    key("projections_disjoint", &OverlapTests::projectionsDisjoint),
    key("unresolved", &OverlapTests::unresolved),
    key("swapped", &OverlapTests::swapped),
    key("ms", &OverlapTests::ms)};

template <> inline constexpr auto kKeys<PainterResult> = std::tuple{
    derived<PainterResult>("key", [](const PainterResult &p) { return OJson(painterKeyName(p.key)); }),
    key("triangles_drawn", &PainterResult::trianglesDrawn),
    key("fragments", &PainterResult::fragments),
    key("covered_pixels", &PainterResult::coveredPixels),
    key("wrong_pixels", &PainterResult::wrongPixels),
    key("tie_pixels", &PainterResult::tiePixels),
    key("edge_pixels", &PainterResult::edgePixels),
    key("overlaps", &PainterResult::overlaps)};

template <> inline constexpr auto kKeys<BspViewResult> = std::tuple{
    key("pieces_drawn", &BspViewResult::piecesDrawn),
    key("wrong_pixels", &BspViewResult::wrongPixels),
    key("tie_pixels", &BspViewResult::tiePixels),
    key("edge_pixels", &BspViewResult::edgePixels),
    key("back_to_front", &BspViewResult::backToFront),
    key("front_to_back", &BspViewResult::frontToBack),
    key("traverse_ms", &BspViewResult::traverseMs)};

template <> inline constexpr auto kKeys<ABufferResult> = std::tuple{
    derived<ABufferResult>("ran", [](const ABufferResult &) { return OJson(true); }),
    key("fragments", &ABufferResult::fragments),
    key("covered_pixels", &ABufferResult::coveredPixels),
    key("average_list_length", &ABufferResult::averageListLength),
    key("max_list_length", &ABufferResult::maxListLength),
    key("list_histogram", &ABufferResult::listHistogram),
    key("memory_bytes", &ABufferResult::memoryBytes),
    key("transparent_fragments", &ABufferResult::transparentFragments),
    key("edge_pixels", &ABufferResult::edgePixels),
    key("ms", &ABufferResult::ms)};

// The tree the ordering audit builds once per scene (report.bsp_tree, when it ran).
template <> inline constexpr auto kKeys<BspStats> = std::tuple{
    derived<BspStats>("ran", [](const BspStats &) { return OJson(true); }),
    key("triangles_in", &BspStats::trianglesIn),
    key("pieces", &BspStats::pieces),
    key("triangles_out", &BspStats::trianglesOut),
    key("splits", &BspStats::splits),
    key("split_sources", &BspStats::splitSources),
    key("degenerate_pieces", &BspStats::degeneratePieces),
    key("nodes", &BspStats::nodes),
    key("depth", &BspStats::depth),
    key("average_leaf_depth", &BspStats::averageLeafDepth),
    key("predicate_calls", &BspStats::predicateCalls),
    key("build_ms", &BspStats::buildMs),
    key("memory_bytes", &BspStats::memoryBytes)};

// ---- The raycast stage's cross-check and secondary rays (view.raycast) --------------------------

template <> inline constexpr auto kKeys<CrossCheck::Example> = std::tuple{
    key("x", &CrossCheck::Example::x),
    key("y", &CrossCheck::Example::y),
    key("zbuffer_id", &CrossCheck::Example::zbufferId),
    key("raycast_id", &CrossCheck::Example::raycastId)};

template <> inline constexpr auto kKeys<CrossCheck> = std::tuple{
    key("pixels", &CrossCheck::pixels),
    key("agree", &CrossCheck::agree),
    key("edge", &CrossCheck::edge),
    key("tie", &CrossCheck::tie),
    key("genuine", &CrossCheck::genuine),
    key("one_sided_background", &CrossCheck::oneSidedBackground),
    key("culled", &CrossCheck::culled),
    key("recast", &CrossCheck::recast),
    key("max_relative_depth_difference", &CrossCheck::maxRelativeDepthDifference),
    key("genuine_examples", &CrossCheck::genuineExamples),
    key("ms", &CrossCheck::ms)};

template <> inline constexpr auto kKeys<EffectsStats> = std::tuple{
    derived<EffectsStats>("rays",
                          [](const EffectsStats &e) {
                              return OJson{{"primary", e.primaryRays},
                                           {"shadow", e.shadowRays},
                                           {"reflection", e.reflectionRays},
                                           {"refraction", e.refractionRays}};
                          }),
    key("primary_hits", &EffectsStats::primaryHits),
    key("secondary_hits", &EffectsStats::secondaryHits),
    key("total_internal_reflections", &EffectsStats::totalInternalReflections),
    key("terminated_by_depth", &EffectsStats::terminatedByDepth),
    key("deepest", &EffectsStats::deepest),
    key("reflection_weight", &EffectsStats::reflectionWeight),
    key("refraction_weight", &EffectsStats::refractionWeight),
    key("ms", &EffectsStats::ms)};

template <> inline constexpr auto kKeys<LightShadowStats> = std::tuple{
    key("name", &LightShadowStats::name),
    key("shadow_rays", &LightShadowStats::shadowRays),
    key("lit_pixels", &LightShadowStats::litPixels),
    key("shadowed_pixels", &LightShadowStats::shadowedPixels),
    key("facing_away_pixels", &LightShadowStats::facingAwayPixels)};

// ---- The culling audit (view.audit) -------------------------------------------------------------

template <> inline constexpr auto kKeys<ReferenceVisibility> = std::tuple{
    key("triangles_in", &ReferenceVisibility::trianglesIn),
    key("visible_triangles", &ReferenceVisibility::visibleTriangles),
    key("visible_objects", &ReferenceVisibility::visibleObjects),
    key("covered_pixels", &ReferenceVisibility::coveredPixels),
    key("back_winding", &ReferenceVisibility::backWinding),
    key("fragments", &ReferenceVisibility::fragments)};

template <> inline constexpr auto kKeys<FalseCullOffender> = std::tuple{
    key("object", &FalseCullOffender::object),
    key("name", &FalseCullOffender::name),
    key("triangles", &FalseCullOffender::triangles),
    key("pixels", &FalseCullOffender::pixels)};

// audit.false_culls.by_stage.NAME (the stage's name is its key there).
template <> inline constexpr auto kKeys<StageCullAudit> = std::tuple{
    key("triangles_culled", &StageCullAudit::trianglesCulled),
    key("objects_culled", &StageCullAudit::objectsCulled),
    key("false_cull_triangles", &StageCullAudit::falseCullTriangles),
    key("false_cull_objects", &StageCullAudit::falseCullObjects),
    key("false_cull_pixels", &StageCullAudit::falseCullPixels),
    derived<StageCullAudit>("false_cull_nearest",
                            [](const StageCullAudit &s) {
                                return s.falseCullPixels ? value(s.falseCullNearest) : OJson(nullptr);
                            }),
    key("snapped_triangles", &StageCullAudit::snappedTriangles),
    key("snapped_pixels", &StageCullAudit::snappedPixels),
    derived<StageCullAudit>("design_far_plane",
                            [](const StageCullAudit &s) { return positiveOrNull(s.designFarPlane); }),
    key("beyond_far_plane_triangles", &StageCullAudit::beyondFarPlaneTriangles),
    key("beyond_far_plane_pixels", &StageCullAudit::beyondFarPlanePixels),
    derived<StageCullAudit>("beyond_far_plane_nearest",
                            [](const StageCullAudit &s) {
                                return s.beyondFarPlanePixels ? value(s.beyondFarPlaneNearest) : OJson(nullptr);
                            }),
    key("worst", &StageCullAudit::worst)};

// ---- The z-fighting analysis (view.depth) -------------------------------------------------------

// depth.formats.NAME (the format's name is its key there).
template <> inline constexpr auto kKeys<ZFightFormatStats> = std::tuple{
    key("bits", &ZFightFormatStats::bits),
    key("fighting_pixels", &ZFightFormatStats::fightingPixels),
    key("coplanar_pixels", &ZFightFormatStats::coplanarPixels),
    key("shared_edge_pixels", &ZFightFormatStats::sharedEdgePixels),
    key("intersection_pixels", &ZFightFormatStats::intersectionPixels),
    key("hotspots", &ZFightFormatStats::hotspots),
    key("out_of_range_pixels", &ZFightFormatStats::outOfRangePixels)};

}  // namespace va::json
