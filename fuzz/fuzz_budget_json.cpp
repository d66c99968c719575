// Budget files (visaudit-budget/1) through loadBudget, for a report whose views are the demo's.
#include "fuzz/fuzz_util.h"
#include "reports/budget.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const std::string path = va::fuzz::writeInput("input.budget.json", data, size);
    va::Budget budget;
    std::string err;
    const bool ok = va::loadBudget(path, {"spawn", "corner"}, &budget, &err);
    va::fuzz::checkResult(ok, err, path);
    return 0;
}
