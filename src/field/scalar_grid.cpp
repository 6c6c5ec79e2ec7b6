// metariver field: ScalarGrid storage.
#include <metariver/field.h>

#include <algorithm>

namespace mr {

void ScalarGrid::reset(int nx_, int ny_, int nz_, Vec3 origin_, float spacing_, float fill) {
    nx = std::max(nx_, 0);
    ny = std::max(ny_, 0);
    nz = std::max(nz_, 0);
    origin = origin_;
    spacing = spacing_;
    values.resize(size());  // keeps capacity when shrinking or regrowing within it
    std::fill(values.begin(), values.end(), fill);
}

}  // namespace mr
