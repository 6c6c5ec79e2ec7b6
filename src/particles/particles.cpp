#include <metariver/particles.h>

namespace mr {

void Particles::resize(size_t n) {
    position.assign(n, Vec3(0.0f));
    last_position.assign(n, Vec3(0.0f));
    velocity.assign(n, Vec3(0.0f));
    force.assign(n, Vec3(0.0f));
    active.assign(n, 0);
    id.resize(n);
    birth_frame.assign(n, 0);
    for (size_t i = 0; i < n; ++i) id[i] = static_cast<uint32_t>(i);
}

size_t Particles::active_count() const {
    size_t n = 0;
    for (uint8_t a : active) n += a;
    return n;
}

void Particles::gather_active_positions(std::vector<Vec3>& out) const {
    out.clear();
    for (size_t i = 0; i < position.size(); ++i)
        if (active[i]) out.push_back(position[i]);
}

}  // namespace mr
