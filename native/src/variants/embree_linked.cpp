// Embree as the static linker bound it (embree_api.h): the core built against Debian's libraries.
#include "../embree_api.h"

namespace ps {

const EmbreeApi& embree_api() {
    static const EmbreeApi api = [] {
        EmbreeApi a;
#define PS_EMBREE_ADDRESS(name) a.name = &::name;
        PS_EMBREE_FUNCTIONS(PS_EMBREE_ADDRESS)
#undef PS_EMBREE_ADDRESS
        return a;
    }();
    return api;
}

}  // namespace ps
