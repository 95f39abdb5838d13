// Compiled (not linked) with the include paths of what links fremen_server: storage's public API
// is visible (tests/layering/CMakeLists.txt).
#include "storage/map_store.h"
#include "storage/store.h"
