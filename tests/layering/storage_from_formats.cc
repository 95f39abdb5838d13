// Compiled with the include paths of what links fremen_formats, which does not link storage: no
// storage header is visible, so this must fail to compile (tests/layering/CMakeLists.txt).
#include "storage/map_info.h"
