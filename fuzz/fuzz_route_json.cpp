// Route files (visaudit-route/1) through loadRouteFile for a z-up scene, then their frames: a route
// that loads gives frames whose cameras the camera model accepts (docs/routes.md).
#include "analysis/load/route.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const std::string path = va::fuzz::writeInput("input.route.json", data, size);
    va::Scene scene;
    scene.up = 'z';
    scene.path = "fuzz";
    va::Route route;
    std::string err;
    const bool ok = va::loadRouteFile(path, scene, &route, &err);
    va::fuzz::checkResult(ok, err, path);
    if (!ok) return 0;
    route.sampling.kind = va::RouteSampling::Kind::count;
    route.sampling.count = 33;
    for (const va::ViewSpec &v : va::routeViews(route)) {
        va::Camera cam;
        std::string why;
        if (!va::makeCamera(v.camera, &cam, &why)) {
            std::fprintf(stderr, "fuzz: %s loaded, but frame '%s' has no camera: %s\n", path.c_str(), v.name.c_str(),
                         why.c_str());
            std::abort();
        }
    }
    return 0;
}
