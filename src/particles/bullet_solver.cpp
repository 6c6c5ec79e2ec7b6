// The paper's engine-physics mode (section 2.4) on Bullet Physics 3, and its future
// work: the same rigid spheres with the paper's spring forces (eq. 3) as external
// forces.
//
// Setup as Bullet's own demos (and ../shared/peers/w2_bullet.cpp): default collision
// configuration, dispatcher, btDbvtBroadphase, sequential-impulse solver,
// btDiscreteDynamicsWorld. One shared btSphereShape; the terrain is either
//  - btBvhTriangleMeshShape over Terrain::vertices()/indices() (no copy: the shape
//    references the terrain's arrays), i.e. exactly the triangles the own solver
//    collides with, or
//  - btHeightfieldTerrainShape over the same samples. Bullet centres a heightfield on
//    its bounding box, so the body sits at ((W-1)s/2, (minH+maxH)/2, (H-1)s/2) and the
//    shape is scaled by (s, 1, s). Its default split (flipQuadEdges = false) cuts
//    every cell along (x+1, z)-(x, z+1), which is the terrain's diagonal
//    (c+1)-(c+W); tests check both shapes give the same triangles and ray hits.
// Spheres are in collision group DefaultFilter and see only StaticFilter (the terrain)
// unless particle_collisions is on, so Bullet never even pairs two spheres.
// Sphere-terrain contacts go through adjust_terrain_contact (internal edges, contact
// points through the centre, one-sided terrain); without it a sphere dropped on flat
// ground is kicked sideways by a neighbouring triangle's edge and rolls for ever.
// Spawning is the own solvers' (Emitters, solver_parts.h: the same draws in the same
// order); a spawn point less than a radius above the ground is raised to one radius
// above it, and each (re)spawn places its body (Impl::reset).
//
// Per internal step (Bullet's fixed step):
//   pre-tick (springs on): forces = gravity + eq. 3 on the bodies' current positions,
//     as applyCentralForce(a * mass) after clearing what stepSimulation applied once.
//   post-tick: respawn spheres outside the terrain's rectangle or below its bounds,
//     count tunneled (centre > kTunnelEpsilon below the triangle mesh), particle steps
//     and sphere-terrain contact manifolds.
#include <metariver/bullet_solver.h>
#include <metariver/solver_parts.h>

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionDispatch/btInternalEdgeUtility.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/CollisionShapes/btTriangleShape.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace mr {

namespace {

btVector3 bt(const Vec3& v) { return btVector3(v.x, v.y, v.z); }
Vec3 mr_vec(const btVector3& v) { return Vec3(v.x(), v.y(), v.z()); }

constexpr int kSphereGroup = btBroadphaseProxy::DefaultFilter;
constexpr int kTerrainGroup = btBroadphaseProxy::StaticFilter;

/// Quantized BVH nodes address at most 2^21 triangles per mesh part.
constexpr size_t kMaxQuantizedTriangles = size_t(1) << 21;

/// Bullet's contact-added hook (a process-wide function pointer, the same for every
/// solver). Contacts of a sphere with the terrain's triangles:
///  1. on an internal edge or vertex, take the face normal (btAdjustInternalEdgeContacts):
///     a sphere near a shared edge is otherwise pushed sideways by the neighbour
///     triangle's edge normal;
///  2. the contact points are put on the line through the sphere's centre along that
///     normal (keeping Bullet's distance): an off-centre point under a vertical impulse
///     would spin the sphere, and friction would turn the spin into rolling;
///  3. a sphere whose centre is below the terrain surface is pushed up along the face
///     normal under it, by its depth plus its radius: Bullet's triangles are two-sided
///     and would push it further down, but a heightfield terrain has only one side.
bool adjust_terrain_contact(btManifoldPoint& cp, const btCollisionObjectWrapper* w0, int part0, int index0,
                            const btCollisionObjectWrapper* w1, int part1, int index1) {
    // Each call returns at once unless its first wrapper is a triangle of a mesh or
    // heightfield that carries edge info.
    btAdjustInternalEdgeContacts(cp, w1, w0, part1, index1);
    btAdjustInternalEdgeContacts(cp, w0, w1, part0, index0);
    const bool a_sphere = w0->getCollisionShape()->getShapeType() == SPHERE_SHAPE_PROXYTYPE;
    const bool b_sphere = w1->getCollisionShape()->getShapeType() == SPHERE_SHAPE_PROXYTYPE;
    if (a_sphere == b_sphere) return true;  // sphere-sphere contacts are exact already
    const btCollisionObjectWrapper* sw = a_sphere ? w0 : w1;
    const btCollisionObjectWrapper* tw = a_sphere ? w1 : w0;
    const auto* terrain = static_cast<const Terrain*>(tw->getCollisionObject()->getUserPointer());
    const btVector3 c = sw->getWorldTransform().getOrigin();
    const btScalar r = static_cast<const btSphereShape*>(sw->getCollisionShape())->getRadius();
    const float depth = terrain && terrain->contains_xz(c.x(), c.z()) ? terrain->height_mesh(c.x(), c.z()) - c.y() : 0.0f;
    if (depth > 0.0f) {
        const Vec3 up = terrain->normal_mesh(c.x(), c.z());
        const btVector3 face(up.x, up.y, up.z);
        cp.m_distance1 = -(depth * up.y + r);  // the sphere's lowest point below the face's plane
        cp.m_normalWorldOnB = a_sphere ? face : -face;
    } else if (tw->getCollisionShape()->getShapeType() == TRIANGLE_SHAPE_PROXYTYPE) {
        // A contact that now carries this triangle's face normal (a face contact, or an
        // internal-edge contact the utility turned to the face): its distance is the
        // sphere's distance to the face's plane, not to the edge (which is shallower and
        // would let the sphere sink until the edge distance reaches zero).
        const auto* tri = static_cast<const btTriangleShape*>(tw->getCollisionShape());
        const btTransform& xf = tw->getWorldTransform();
        const btVector3 v0 = xf(tri->m_vertices1[0]);
        btVector3 face = xf.getBasis() * (tri->m_vertices1[1] - tri->m_vertices1[0]).cross(tri->m_vertices1[2] - tri->m_vertices1[0]);
        face.normalize();
        const btVector3 n_towards_sphere = a_sphere ? cp.m_normalWorldOnB : -cp.m_normalWorldOnB;
        if (std::fabs(face.dot(n_towards_sphere)) > 0.9999f) {
            if (face.dot(n_towards_sphere) < 0) face = -face;
            cp.m_distance1 = (c - v0).dot(face) - r;
        }
    }
    const btVector3 n = cp.m_normalWorldOnB;  // from B towards A
    if (a_sphere) {
        cp.m_positionWorldOnA = c - n * r;
        cp.m_positionWorldOnB = cp.m_positionWorldOnA - n * cp.m_distance1;
    } else {
        cp.m_positionWorldOnB = c + n * r;
        cp.m_positionWorldOnA = cp.m_positionWorldOnB + n * cp.m_distance1;
    }
    cp.m_localPointA = w0->getWorldTransform().invXform(cp.m_positionWorldOnA);
    cp.m_localPointB = w1->getWorldTransform().invXform(cp.m_positionWorldOnB);
    return true;
}

}  // namespace

struct BulletSolver::Impl final : SlotState {
    Impl(const Terrain& t, const SpawnDef& sp, SpringDef sg, IntegratorDef in, BulletDef b, uint32_t seed)
        : terrain(t),
          springs(sg),
          integrator(in),
          def(b),
          pool(static_cast<size_t>(std::max(sp.count, 0)), sp.center),
          // A sphere is a collider: one drawn less than a radius above the ground starts
          // a radius above it (an engine would push it out; the own solver's points stay).
          emitters(t, EmitterDef{.spawn = sp, .on_ground = true, .ground_lift = b.sphere_radius, .gravity = in.gravity},
                   seed),
          sphere(b.sphere_radius) {
        pool.slots = this;
    }

    ~Impl() {
        for (auto& body : bodies)
            if (body->isInWorld()) world->removeRigidBody(body.get());
        if (terrain_body) world->removeRigidBody(terrain_body.get());
    }

    const Terrain& terrain;
    SpringDef springs;
    IntegratorDef integrator;
    BulletDef def;
    ParticlePool pool;  ///< the particles' view of the bodies, the frame and the counters
    Particles& particles = pool.particles;
    Emitters emitters;
    uint64_t internal_steps = 0;

    // Shapes and bodies are declared before the world so they outlive it.
    std::vector<float> heights;  ///< heightfield samples, row i (z) major: heights[i*W + j]
    std::unique_ptr<btTriangleIndexVertexArray> mesh;
    std::unique_ptr<btCollisionShape> terrain_shape;
    std::unique_ptr<btRigidBody> terrain_body;
    std::unique_ptr<btTriangleInfoMap> edge_info;  ///< internal-edge data of the terrain shape
    Vec3 terrain_origin{0.0f};  ///< world position of the terrain shape's local origin
    btSphereShape sphere;
    btVector3 sphere_inertia{0, 0, 0};
    std::vector<std::unique_ptr<btRigidBody>> bodies;

    std::unique_ptr<btDefaultCollisionConfiguration> config;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    std::unique_ptr<btDbvtBroadphase> broadphase;
    std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
    std::unique_ptr<btDiscreteDynamicsWorld> world;

    void build();
    void build_terrain();
    /// Slot i was (re)spawned (Emitters): its body goes where its particle is, at rest
    /// but for the initial velocity.
    void reset(size_t i) override;
    void swap(size_t i, size_t j) override { std::swap(bodies[i], bodies[j]); }
    void permute(std::span<const uint32_t> perm) override;
    void pre_tick();
    void post_tick();
    void sync_view();
    float depth_below_surface(const Vec3& p) const {
        if (!terrain.contains_xz(p.x, p.z)) return 0.0f;
        return terrain.height_mesh(p.x, p.z) - p.y;
    }

    static void pre_tick_cb(btDynamicsWorld* w, btScalar) { static_cast<Impl*>(w->getWorldUserInfo())->pre_tick(); }
    static void post_tick_cb(btDynamicsWorld* w, btScalar) { static_cast<Impl*>(w->getWorldUserInfo())->post_tick(); }
};

void BulletSolver::Impl::build_terrain() {
    const int w = terrain.columns(), h = terrain.rows();
    const float s = terrain.area_scale();
    if (def.terrain == BulletTerrainShape::Mesh) {
        const auto verts = terrain.vertices();
        const auto idx = terrain.indices();
        static_assert(sizeof(Vec3) == 3 * sizeof(float), "Bullet reads the vertices with a stride of 12 bytes");
        // Bullet only reads these arrays; its interface takes non-const pointers.
        mesh = std::make_unique<btTriangleIndexVertexArray>(
            static_cast<int>(terrain.triangle_count()),
            reinterpret_cast<int*>(const_cast<uint32_t*>(idx.data())), static_cast<int>(3 * sizeof(uint32_t)),
            static_cast<int>(verts.size()), const_cast<btScalar*>(&verts.data()->x),
            static_cast<int>(sizeof(Vec3)));
        const bool quantized = terrain.triangle_count() < kMaxQuantizedTriangles;
        auto shape = std::make_unique<btBvhTriangleMeshShape>(mesh.get(), quantized, true);
        edge_info = std::make_unique<btTriangleInfoMap>();
        btGenerateInternalEdgeInfo(shape.get(), edge_info.get());
        terrain_shape = std::move(shape);
        terrain_origin = Vec3(0.0f);
    } else {
        heights.resize(static_cast<size_t>(w) * h);
        float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
        for (int i = 0; i < h; ++i) {
            for (int j = 0; j < w; ++j) {
                const float y = terrain.sample(i, j);
                heights[static_cast<size_t>(i) * w + j] = y;
                lo = std::min(lo, y);
                hi = std::max(hi, y);
            }
        }
        auto hf = std::make_unique<btHeightfieldTerrainShape>(w, h, heights.data(), lo, hi, 1, false);
        hf->setLocalScaling(btVector3(s, 1.0f, s));
        edge_info = std::make_unique<btTriangleInfoMap>();
        btGenerateInternalEdgeInfo(hf.get(), edge_info.get());
        terrain_shape = std::move(hf);
        // Bullet centres the heightfield on its bounding box (x, z and height).
        terrain_origin = Vec3(0.5f * static_cast<float>(w - 1) * s, 0.5f * (lo + hi), 0.5f * static_cast<float>(h - 1) * s);
    }
    btRigidBody::btRigidBodyConstructionInfo ci(0.0f, nullptr, terrain_shape.get());
    ci.m_friction = def.friction;
    ci.m_restitution = def.restitution;
    terrain_body = std::make_unique<btRigidBody>(ci);
    terrain_body->setUserPointer(const_cast<Terrain*>(&terrain));  // read by adjust_terrain_contact
    terrain_body->setCollisionFlags(terrain_body->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
    gContactAddedCallback = &adjust_terrain_contact;
    btTransform xf;
    xf.setIdentity();
    xf.setOrigin(bt(terrain_origin));
    terrain_body->setWorldTransform(xf);
    world->addRigidBody(terrain_body.get(), kTerrainGroup, btBroadphaseProxy::AllFilter ^ kTerrainGroup);
}

void BulletSolver::Impl::build() {
    config = std::make_unique<btDefaultCollisionConfiguration>();
    dispatcher = std::make_unique<btCollisionDispatcher>(config.get());
    broadphase = std::make_unique<btDbvtBroadphase>();
    solver = std::make_unique<btSequentialImpulseConstraintSolver>();
    world = std::make_unique<btDiscreteDynamicsWorld>(dispatcher.get(), broadphase.get(), solver.get(), config.get());
    world->setGravity(btVector3(0.0f, -integrator.gravity, 0.0f));
    world->getSolverInfo().m_numIterations = def.solver_iterations;
    world->setInternalTickCallback(&Impl::post_tick_cb, this, false);
    if (def.springs && springs.stiffness != 0.0f) world->setInternalTickCallback(&Impl::pre_tick_cb, this, true);
    build_terrain();

    sphere.calculateLocalInertia(def.mass, sphere_inertia);
    const size_t n = pool.size();
    bodies.reserve(n);
    for (size_t i = 0; i < n; ++i) {
        btRigidBody::btRigidBodyConstructionInfo ci(def.mass, nullptr, &sphere, sphere_inertia);
        ci.m_friction = def.friction;
        ci.m_restitution = def.restitution;
        bodies.push_back(std::make_unique<btRigidBody>(ci));
        btRigidBody& b = *bodies.back();
        if (!def.sleep || def.springs) b.setActivationState(DISABLE_DEACTIVATION);
        if (def.ccd) {
            b.setCcdMotionThreshold(0.5f * def.sphere_radius);
            b.setCcdSweptSphereRadius(0.9f * def.sphere_radius);
        }
    }
}

void BulletSolver::Impl::reset(size_t i) {
    const Vec3 p = particles.position[i];
    const Vec3 v = particles.velocity[i];
    btRigidBody& b = *bodies[i];
    btTransform xf;
    xf.setIdentity();
    xf.setOrigin(bt(p));
    b.setWorldTransform(xf);
    b.setInterpolationWorldTransform(xf);
    b.setLinearVelocity(bt(v));
    b.setAngularVelocity(btVector3(0, 0, 0));
    b.setInterpolationLinearVelocity(bt(v));
    b.setInterpolationAngularVelocity(btVector3(0, 0, 0));
    // Forces stay: between frames they are clear; inside a step (a respawn from the
    // post-tick) they hold the gravity stepSimulation applied for its remaining steps.
    if (!b.isInWorld()) {
        const int mask = kTerrainGroup | (def.particle_collisions ? kSphereGroup : 0);
        world->addRigidBody(&b, kSphereGroup, mask);
    } else {
        world->updateSingleAabb(&b);  // teleported: the broadphase box follows now
    }
    b.activate(true);
}

void BulletSolver::Impl::permute(std::span<const uint32_t> perm) {
    std::vector<std::unique_ptr<btRigidBody>> sorted(perm.size());  // the prefix; the rest keep theirs
    for (size_t k = 0; k < perm.size(); ++k) sorted[k] = std::move(bodies[perm[k]]);
    std::move(sorted.begin(), sorted.end(), bodies.begin());
}

void BulletSolver::Impl::pre_tick() {
    // stepSimulation applies gravity once per call and keeps forces for all its internal
    // steps; springs change every step, so rebuild the total force here.
    Particles& p = particles;
    for (size_t i = 0; i < p.size(); ++i) {
        p.force[i] = Vec3(0.0f);
        if (p.active[i]) p.position[i] = mr_vec(bodies[i]->getWorldTransform().getOrigin());
    }
    add_spring_forces_pairs(p, springs);
    for (size_t i = 0; i < p.size(); ++i) {
        if (!p.active[i]) continue;
        btRigidBody& b = *bodies[i];
        b.clearForces();
        b.applyGravity();
        b.applyCentralForce(bt(p.force[i] * def.mass));
    }
}

void BulletSolver::Impl::post_tick() {
    ++internal_steps;
    SolverCounters& counters = pool.counters;
    for (int m = 0; m < dispatcher->getNumManifolds(); ++m) {
        const btPersistentManifold* pm = dispatcher->getManifoldByIndexInternal(m);
        if (pm->getNumContacts() == 0) continue;
        if (pm->getBody0() == terrain_body.get() || pm->getBody1() == terrain_body.get()) ++counters.collisions;
    }
    for (size_t i = 0; i < particles.size(); ++i) {
        if (!particles.active[i]) continue;
        ++counters.particle_steps;
        const Vec3 pos = mr_vec(bodies[i]->getWorldTransform().getOrigin());
        if (outside_terrain(terrain, pos)) {
            ++counters.respawned;
            emitters.spawn(pool, i);
            continue;
        }
        if (depth_below_surface(pos) > kTunnelEpsilon) ++counters.tunneled;
    }
}

void BulletSolver::Impl::sync_view() {
    for (size_t i = 0; i < particles.size(); ++i) {
        if (!particles.active[i]) continue;
        const btRigidBody& b = *bodies[i];
        particles.position[i] = mr_vec(b.getWorldTransform().getOrigin());
        particles.velocity[i] = mr_vec(b.getLinearVelocity());
    }
}

BulletSolver::BulletSolver(const Terrain& terrain, SpawnDef spawn, SpringDef springs, IntegratorDef integrator,
                           BulletDef bullet, uint32_t seed)
    : impl_(std::make_unique<Impl>(terrain, spawn, springs, integrator, bullet, seed)) {
    impl_->build();
}

BulletSolver::~BulletSolver() = default;

void BulletSolver::step_frame(float frame_dt) {
    Impl& s = *impl_;
    s.emitters.activate_due(s.pool);  // the paper's activation (a flow rate is the own solvers')
    for (size_t i = 0; i < s.particles.size(); ++i) s.particles.last_position[i] = s.particles.position[i];
    const float dt = s.integrator.fixed_dt > 0.0f ? s.integrator.fixed_dt : frame_dt;
    s.world->stepSimulation(dt, s.def.max_substeps, s.def.fixed_dt);
    s.sync_view();
    ++s.pool.frame;
}

const Particles& BulletSolver::particles() const { return impl_->particles; }
const SolverCounters& BulletSolver::counters() const { return impl_->pool.counters; }
uint64_t BulletSolver::frame() const { return impl_->pool.frame; }
uint64_t BulletSolver::internal_steps() const { return impl_->internal_steps; }
void BulletSolver::set_spawn_center(const Vec3& center) { impl_->emitters.set_center(center); }

void BulletSolver::pour(const Vec3& center, int count) { impl_->emitters.pour(impl_->pool, center, count); }

size_t BulletSolver::awake_count() const {
    size_t n = 0;
    for (size_t i = 0; i < impl_->bodies.size(); ++i)
        if (impl_->particles.active[i] && impl_->bodies[i]->isActive()) ++n;
    return n;
}

std::optional<Vec3> BulletSolver::raycast_terrain(const Vec3& from, const Vec3& to) const {
    btCollisionWorld::ClosestRayResultCallback cb(bt(from), bt(to));
    cb.m_collisionFilterGroup = kSphereGroup;
    cb.m_collisionFilterMask = kTerrainGroup;
    impl_->world->rayTest(bt(from), bt(to), cb);
    if (!cb.hasHit()) return std::nullopt;
    return mr_vec(cb.m_hitPointWorld);
}

namespace {
struct CollectTriangles final : btTriangleCallback {
    Vec3 offset{0.0f};
    std::vector<std::array<Vec3, 3>>* out = nullptr;
    void processTriangle(btVector3* t, int, int) override {
        out->push_back({mr_vec(t[0]) + offset, mr_vec(t[1]) + offset, mr_vec(t[2]) + offset});
    }
};
}  // namespace

std::vector<std::array<Vec3, 3>> BulletSolver::terrain_triangles(const Aabb& box) const {
    std::vector<std::array<Vec3, 3>> out;
    CollectTriangles cb;
    cb.offset = impl_->terrain_origin;
    cb.out = &out;
    const auto* concave = static_cast<const btConcaveShape*>(impl_->terrain_shape.get());
    concave->processAllTriangles(&cb, bt(box.min - impl_->terrain_origin), bt(box.max - impl_->terrain_origin));
    return out;
}

}  // namespace mr
