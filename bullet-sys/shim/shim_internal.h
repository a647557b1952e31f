// shim_internal.h: what the shim's files share; private to bullet-sys (bindgen reads only snake_shim.h,
// the FFI contract). The files, by concern:
// - snake_shim.cpp: the C API of snake_shim.h (every extern "C" function, the guard that turns C++
//   exceptions into status codes, the thread-local last error), the world and the programmatic bodies;
// - shim_urdf.cpp: URDF robots (BulletURDFImporter + ConvertURDF2Bullet);
// - shim_skin.cpp: the skin-friction law inside the contact solver (SkinSolver).
#ifndef SNAKE_SHIM_INTERNAL_H
#define SNAKE_SHIM_INTERNAL_H

#include "snake_shim.h"

#include <btBulletDynamicsCommon.h>
#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>

#include <cmath>
#include <memory>
#include <vector>

namespace snake_shim {

// Records `message` as the calling thread's last error (ss_last_error) and returns `code`.
int fail(int code, const char* message);

inline bool finite3(const double* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

// pybullet's MyOverlapFilterCallback in B3_FILTER_GROUPAMASKB_OR_GROUPBMASKA mode (PSCP 781-852).
struct OrFilterCallback : public btOverlapFilterCallback {
    bool needBroadphaseCollision(btBroadphaseProxy* p0, btBroadphaseProxy* p1) const override {
        bool collides = (p0->m_collisionFilterGroup & p1->m_collisionFilterMask) != 0;
        collides = collides || (p1->m_collisionFilterGroup & p0->m_collisionFilterMask);
        return collides;
    }
};

// A link's skin-friction coefficients (see shim_skin.cpp).
struct Skin {
    double forward, backward, transverse;
    btVector3 axis;  // unit, in the collider's (centre-of-mass) frame
};

// The contact solver of every world: Bullet's btMultiBodyConstraintSolver with the skin-friction law for
// the contacts of links in `skins` (shim_skin.cpp). `skins` must outlive the solver.
std::unique_ptr<btMultiBodyConstraintSolver> new_skin_solver(const std::vector<Skin>* skins);

}  // namespace snake_shim

struct ss_world {
    // Declaration order is construction order; destruction runs in reverse, world first.
    std::unique_ptr<btDefaultCollisionConfiguration> config;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    std::unique_ptr<snake_shim::OrFilterCallback> filter;
    std::unique_ptr<btHashedOverlappingPairCache> pair_cache;
    std::unique_ptr<btDbvtBroadphase> broadphase;
    std::vector<snake_shim::Skin> skins;  // before the solver, which reads it
    std::unique_ptr<btMultiBodyConstraintSolver> solver;  // a SkinSolver
    std::unique_ptr<btMultiBodyDynamicsWorld> world;
    // Heightfield samples, which their btHeightfieldTerrainShape reads in place: declared before the
    // shapes so that they outlive them.
    std::vector<std::unique_ptr<btScalar[]>> heightfields;
    std::vector<std::unique_ptr<btCollisionShape>> shapes;
    std::vector<std::unique_ptr<btMultiBodyLinkCollider>> colliders;
    std::vector<std::unique_ptr<btMultiBodyConstraint>> constraints;
    std::vector<std::unique_ptr<btMultiBody>> bodies;
    // Per body, the basis of each link's inertial frame in its link frame (base first); empty when every
    // inertial frame is the link frame (createMultiBody bodies). Skin axes are given in link frames.
    std::vector<std::vector<btMatrix3x3>> inertial_bases;
    btScalar dt = btScalar(1.) / btScalar(240.);

    ~ss_world() {
        if (world) {
            for (auto& c : constraints) world->removeMultiBodyConstraint(c.get());
            for (auto& b : bodies) world->removeMultiBody(b.get());
            for (auto& c : colliders) world->removeCollisionObject(c.get());
        }
    }

    btMultiBody* body(int index) const {
        if (index < 0 || index >= (int)bodies.size()) return nullptr;
        return bodies[index].get();
    }
};

namespace snake_shim {

// pybullet's createJointMotors on `body` (snake_shim.cpp).
void add_default_motors(ss_world* w, btMultiBody* body);

// Why the robot `d` cannot be built (a message for ss_last_error), or null when it can (shim_urdf.cpp).
const char* check_urdf(const ss_urdf_desc* d);

// Builds the robot `d`, which has passed check_urdf, as pybullet's loadURDF does (shim_urdf.cpp).
int build_urdf(ss_world* w, const ss_urdf_desc* d, int* body_out);

}  // namespace snake_shim

#endif  // SNAKE_SHIM_INTERNAL_H
