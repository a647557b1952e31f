// snake_shim.cpp: see snake_shim.h. Each step below names the pybullet 3.2.7 code it mirrors; the order
// of calls is part of the contract, because pair order, proxy ids and rounding all follow from it. URDF
// import and the skin-friction solver live in shim_urdf.cpp and shim_skin.cpp (see shim_internal.h).

#include "shim_internal.h"

#include <BulletDynamics/Featherstone/btMultiBodyJointMotor.h>
#include <BulletCollision/CollisionDispatch/btInternalEdgeUtility.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <LinearMath/btQuickprof.h>

#include <cmath>
#include <exception>
#include <memory>
#include <mutex>
#include <new>
#include <string>
#include <vector>

using namespace snake_shim;

namespace {

thread_local std::string g_last_error;

// Bullet's built-in profiler keeps process-wide, unsynchronised state; stepping worlds on several
// threads through it races. Its hooks are replaced by no-ops once, before any world exists.
void profile_enter_noop(const char*) {}
void profile_leave_noop() {}

std::once_flag g_process_setup;

// pybullet's MyContactAddedCallback (PSCP 2099-2103).
bool contact_added(btManifoldPoint& cp, const btCollisionObjectWrapper* colObj0Wrap, int partId0, int index0,
                   const btCollisionObjectWrapper* colObj1Wrap, int partId1, int index1) {
    (void)colObj0Wrap;
    (void)partId0;
    (void)index0;
    btAdjustInternalEdgeContacts(cp, colObj1Wrap, colObj0Wrap, partId1, index1);
    return true;
}

void process_setup() {
    btSetCustomEnterProfileZoneFunc(profile_enter_noop);
    btSetCustomLeaveProfileZoneFunc(profile_leave_noop);
    // pybullet sets this global to 0 in createEmptyDynamicsWorld; every world here uses the same value,
    // so setting it once keeps it constant while worlds step concurrently.
    gDbvtMargin = btScalar(0);
    // pybullet installs this contact callback in createEmptyDynamicsWorld (PSCP 2826); it runs for
    // colliders flagged CF_CUSTOM_MATERIAL_CALLBACK (heightfields) and is a no-op without a triangle
    // info map, which pybullet builds only for GEOM_CONCAVE_INTERNAL_EDGE. Set here for the same path.
    gContactAddedCallback = contact_added;
}

}  // namespace

namespace snake_shim {

int fail(int code, const char* message) {
    g_last_error = message;
    return code;
}

// pybullet's createJointMotors (PSCP 3117): a velocity-0 motor with max impulse 1 on every revolute
// (continuous included) and prismatic joint, in link order, owned by the world.
void add_default_motors(ss_world* w, btMultiBody* body) {
    for (int k = 0; k < body->getNumLinks(); ++k) {
        int type = body->getLink(k).m_jointType;
        if (type != btMultibodyLink::eRevolute && type != btMultibodyLink::ePrismatic) continue;
        float max_motor_impulse = 1.f;
        btScalar desired_velocity = 0.f;
        auto motor = std::unique_ptr<btMultiBodyJointMotor>(
            new btMultiBodyJointMotor(body, k, 0, desired_velocity, max_motor_impulse));
        motor->setPositionTarget(0, 0);
        motor->setVelocityTarget(0, 1);
        body->getLink(k).m_userPtr = motor.get();
        w->world->addMultiBodyConstraint(motor.get());
        motor->finalizeMultiDof();
        w->constraints.push_back(std::move(motor));
    }
}

}  // namespace snake_shim

namespace {

// The pybullet programmatic-body conversion (ConvertURDF2BulletInternal, U2B 202-768, and the
// post-processing in ConvertURDF2Bullet, U2B 868-895) for a body whose links all use `shape`, whose
// inertial frames are the identity, and whose joints are revolute. `link_*` arrays are in pybullet's
// link order, which for a chain equals Bullet's depth-first order.
int build_multibody(ss_world* w, btCollisionShape* shape, double base_mass, const double* base_pos,
                    const double* base_orn, int num_links, const double* link_masses,
                    const double* link_positions, const double* link_orientations, const int* link_parents,
                    const double* link_axes, int* body_out) {
    btTransform root;
    root.setOrigin(btVector3(base_pos[0], base_pos[1], base_pos[2]));
    root.setRotation(btQuaternion(base_orn[0], base_orn[1], base_orn[2], base_orn[3]));

    btTransform identity;
    identity.setIdentity();

    // Base (root link): no parent joint, so linkTransformInWorldSpace = root * identity.
    btScalar mass = base_mass;
    btVector3 inertia(0, 0, 0);
    if (mass != btScalar(0)) shape->calculateLocalInertia(mass, inertia);
    bool fixed_base = (mass == btScalar(0));
    auto mb = std::unique_ptr<btMultiBody>(new btMultiBody(num_links, mass, inertia, fixed_base, false));
    btMultiBody* body = mb.get();

    std::vector<btTransform> link_world(num_links + 1);
    link_world[0] = root * identity;

    auto add_collider = [&](int mb_link, const btTransform& tr) {
        auto col = std::unique_ptr<btMultiBodyLinkCollider>(new btMultiBodyLinkCollider(body, mb_link));
        col->setCollisionShape(shape);
        col->setWorldTransform(tr);
        bool dynamic = !(mb_link < 0 && body->hasFixedBase());
        int group = dynamic ? int(btBroadphaseProxy::DefaultFilter) : int(btBroadphaseProxy::StaticFilter);
        int mask = dynamic ? int(btBroadphaseProxy::AllFilter)
                           : int(btBroadphaseProxy::AllFilter ^ btBroadphaseProxy::StaticFilter);
        // URDF2Bullet flags a heightfield's collider for the contact-added callback (U2B 646-649).
        if (shape->getShapeType() == TERRAIN_SHAPE_PROXYTYPE)
            col->setCollisionFlags(col->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
        w->world->addCollisionObject(col.get(), group, mask);
        if (mb_link >= 0) {
            // Revolute joints are never "all fixed", so no link becomes CF_STATIC_OBJECT.
            body->getLink(mb_link).m_collider = col.get();
        } else {
            if (body->getBaseMass() == btScalar(0))
                col->setCollisionFlags(col->getCollisionFlags() | btCollisionObject::CF_STATIC_OBJECT);
            body->setBaseCollider(col.get());
        }
        w->colliders.push_back(std::move(col));
    };
    add_collider(-1, link_world[0]);

    // Links, depth first from the base in increasing index (a chain keeps the user's order).
    std::vector<int> order;
    std::vector<int> stack;
    stack.push_back(-1);
    while (!stack.empty()) {
        int parent = stack.back();
        stack.pop_back();
        if (parent >= 0) order.push_back(parent);
        for (int child = num_links - 1; child >= 0; --child)
            if (link_parents[child] - 1 == parent) stack.push_back(child);
    }
    if ((int)order.size() != num_links) return fail(SS_ERR_ARGUMENT, "link parents do not form a tree rooted at the base");
    std::vector<int> mb_index(num_links);
    for (int k = 0; k < num_links; ++k) mb_index[order[k]] = k;

    for (int k = 0; k < num_links; ++k) {
        int i = order[k];
        int parent = link_parents[i] - 1;
        int mb_parent = parent < 0 ? -1 : mb_index[parent];

        btTransform parent2joint;
        parent2joint.setOrigin(btVector3(link_positions[3 * i], link_positions[3 * i + 1], link_positions[3 * i + 2]));
        parent2joint.setRotation(btQuaternion(link_orientations[4 * i], link_orientations[4 * i + 1],
                                              link_orientations[4 * i + 2], link_orientations[4 * i + 3]));
        const btTransform& parent_world = link_world[parent + 1];
        link_world[i + 1] = parent_world * parent2joint;

        btScalar link_mass = link_masses[i];
        btVector3 link_inertia(0, 0, 0);
        if (link_mass != btScalar(0)) shape->calculateLocalInertia(link_mass, link_inertia);

        btTransform parent_inertial = identity;  // inertial frames are the link frames
        btTransform local_inertial = identity;
        btTransform offset_in_a = parent_inertial.inverse() * parent2joint;
        btTransform offset_in_b = local_inertial.inverse();
        btQuaternion parent_rot_to_this = offset_in_b.getRotation() * offset_in_a.inverse().getRotation();

        btMultibodyLink& link = body->getLink(k);
        link.m_jointDamping = 0;
        link.m_jointFriction = 0;
        link.m_jointLowerLimit = 1;  // lower > upper: no limit (pybullet's programmatic defaults)
        link.m_jointUpperLimit = -1;
        link.m_jointMaxForce = 0;
        link.m_jointMaxVelocity = 0;

        btVector3 axis(link_axes[3 * i], link_axes[3 * i + 1], link_axes[3 * i + 2]);
        body->setupRevolute(k, link_mass, link_inertia, mb_parent, parent_rot_to_this,
                            quatRotate(offset_in_b.getRotation(), axis), offset_in_a.getOrigin(),
                            -offset_in_b.getOrigin(), true);
        add_collider(k, link_world[i + 1]);
    }

    // Post process (U2B 868-895).
    body->setHasSelfCollision(false);
    body->finalizeMultiDof();
    body->setBaseWorldTransform(root * identity);
    btAlignedObjectArray<btQuaternion> scratch_q;
    btAlignedObjectArray<btVector3> scratch_m;
    body->forwardKinematics(scratch_q, scratch_m);
    body->updateCollisionObjectWorldTransforms(scratch_q, scratch_m);
    w->world->addMultiBody(body);

    // createJointMotors (PSCP 3117); the cube snake's joints are all revolute.
    add_default_motors(w, body);

    *body_out = (int)w->bodies.size();
    w->bodies.push_back(std::move(mb));
    w->inertial_bases.emplace_back();
    return SS_OK;
}

btMultiBodyJointMotor* joint_motor(btMultiBody* body, int joint) {
    return static_cast<btMultiBodyJointMotor*>(const_cast<void*>(body->getLink(joint).m_userPtr));
}

// POSITION_CONTROL on one joint (PSCP 7282-7345). max_velocity is setJointMotorControl2's maxVelocity:
// pybullet.c sends it only when > 0 (b3JointControlSetMaximumVelocity), and the server then calls
// setRhsClamp before anything else; otherwise the clamp stays as it was (+inf from the motor's
// constructor). btMultiBodyJointMotor::createConstraintRows (3.24) clamps the row's target velocity
// kp*erp*(q* - q)/dt + qdot + kd*(qdot* - qdot) to [-clamp, clamp]; the impulse bounds stay +-force*dt.
void set_position_motor(btMultiBody* body, int joint, btScalar dt, double target_pos, double target_vel,
                        double force, double kp, double kd, double max_velocity) {
    btMultiBodyJointMotor* motor = joint_motor(body, joint);
    if (max_velocity > 0) motor->setRhsClamp(max_velocity);
    motor->setVelocityTarget(target_vel, kd);
    btScalar desired = target_pos;
    const btMultibodyLink& link = body->getLink(joint);
    if (link.m_jointLowerLimit <= link.m_jointUpperLimit) btClamp(desired, link.m_jointLowerLimit, link.m_jointUpperLimit);
    motor->setPositionTarget(desired, kp);
    motor->setMaxAppliedImpulse(force * dt);
}

}  // namespace

namespace {
// After a state is set: the link frames and the colliders follow, as pybullet's processInitPoseCommand
// ends (forwardKinematics, then updateCollisionObjectWorldTransforms).
void refresh_transforms(btMultiBody* mb) {
    btAlignedObjectArray<btQuaternion> scratch_q;
    btAlignedObjectArray<btVector3> scratch_m;
    mb->forwardKinematics(scratch_q, scratch_m);
    scratch_q.resize(mb->getNumLinks() + 1);
    scratch_m.resize(mb->getNumLinks() + 1);
    mb->updateCollisionObjectWorldTransforms(scratch_q, scratch_m);
}
}  // namespace

#define SS_GUARD_BEGIN try {
#define SS_GUARD_END                                                              \
    }                                                                             \
    catch (const std::bad_alloc&) { return fail(SS_ERR_EXCEPTION, "out of memory"); } \
    catch (const std::exception& e) { return fail(SS_ERR_EXCEPTION, e.what()); }  \
    catch (...) { return fail(SS_ERR_EXCEPTION, "unknown C++ exception"); }

extern "C" {

const char* ss_last_error(void) { return g_last_error.c_str(); }

ss_world* ss_world_new(void) {
    try {
        std::call_once(g_process_setup, process_setup);
        auto w = std::unique_ptr<ss_world>(new ss_world());
        // createEmptyDynamicsWorld (PSCP 2707-2826).
        w->config.reset(new btDefaultCollisionConfiguration());
        w->dispatcher.reset(new btCollisionDispatcher(w->config.get()));
        w->filter.reset(new OrFilterCallback());
        w->pair_cache.reset(new btHashedOverlappingPairCache());
        w->pair_cache->setOverlapFilterCallback(w->filter.get());
        w->broadphase.reset(new btDbvtBroadphase(w->pair_cache.get()));
        w->broadphase->setVelocityPrediction(0);
        w->solver = new_skin_solver(&w->skins);
        w->world.reset(new btMultiBodyDynamicsWorld(w->dispatcher.get(), w->broadphase.get(), w->solver.get(),
                                                    w->config.get()));
        btMultiBodyDynamicsWorld* world = w->world.get();
        world->setForceUpdateAllAabbs(false);
        world->setGravity(btVector3(0, 0, 0));
        btContactSolverInfo& info = world->getSolverInfo();
        info.m_erp2 = 0.08;
        info.m_frictionERP = 0.2;
        info.m_linearSlop = 0.00001;
        info.m_numIterations = 50;
        info.m_minimumSolverBatchSize = 0;
        info.m_warmstartingFactor = 0.1;
        info.m_leastSquaresResidualThreshold = 1e-7;
        return w.release();
    } catch (const std::exception& e) {
        g_last_error = e.what();
    } catch (...) {
        g_last_error = "unknown C++ exception";
    }
    return nullptr;
}

void ss_world_free(ss_world* world) {
    try {
        delete world;
    } catch (...) {
    }
}

int ss_world_set_gravity(ss_world* w, double gx, double gy, double gz) {
    if (!w) return fail(SS_ERR_NULL, "world is null");
    if (!std::isfinite(gx) || !std::isfinite(gy) || !std::isfinite(gz)) return fail(SS_ERR_ARGUMENT, "gravity must be finite");
    SS_GUARD_BEGIN
    w->world->setGravity(btVector3(gx, gy, gz));
    return SS_OK;
    SS_GUARD_END
}

int ss_world_set_time_step(ss_world* w, double dt) {
    if (!w) return fail(SS_ERR_NULL, "world is null");
    if (!(dt > 0) || !std::isfinite(dt)) return fail(SS_ERR_ARGUMENT, "time step must be positive and finite");
    w->dt = dt;
    return SS_OK;
}

int ss_world_num_bodies(const ss_world* w, int* count) {
    if (!w || !count) return fail(SS_ERR_NULL, "null argument");
    *count = (int)w->bodies.size();
    return SS_OK;
}

int ss_world_add_plane(ss_world* w, int* body_out) {
    if (!w || !body_out) return fail(SS_ERR_NULL, "null argument");
    SS_GUARD_BEGIN
    // createCollisionShape(GEOM_PLANE): btStaticPlaneShape((0,0,1), 0) with margin 0.001.
    auto plane = std::unique_ptr<btCollisionShape>(new btStaticPlaneShape(btVector3(0, 0, 1), 0));
    plane->setMargin(0.001);
    btCollisionShape* shape = plane.get();
    w->shapes.push_back(std::move(plane));
    const double pos[3] = {0, 0, 0};
    const double orn[4] = {0, 0, 0, 1};
    return build_multibody(w, shape, 0.0, pos, orn, 0, nullptr, nullptr, nullptr, nullptr, nullptr, body_out);
    SS_GUARD_END
}

int ss_world_add_static(ss_world* w, const ss_static_desc* d, int* body_out) {
    if (!w || !d || !body_out) return fail(SS_ERR_NULL, "null argument");
    if (!finite3(d->size) || !finite3(d->position) || !finite3(d->orientation) || !std::isfinite(d->orientation[3]))
        return fail(SS_ERR_ARGUMENT, "sizes and pose must be finite");
    const bool heightfield = d->type == SS_GEOM_HEIGHTFIELD;
    if (heightfield) {
        if (d->rows < 2 || d->columns < 2) return fail(SS_ERR_ARGUMENT, "a heightfield needs at least 2 x 2 samples");
        if ((long long)d->rows * (long long)d->columns > (1LL << 26)) return fail(SS_ERR_ARGUMENT, "heightfield too large");
        if (!d->heights) return fail(SS_ERR_NULL, "heights must not be null");
        for (long long i = 0; i < (long long)d->rows * d->columns; ++i)
            if (!std::isfinite(d->heights[i])) return fail(SS_ERR_ARGUMENT, "heights must be finite");
    }
    SS_GUARD_BEGIN
    std::unique_ptr<btCollisionShape> owned;
    // processCreateCollisionShapeCommand (PSCP 4851-5170) with pybullet's default margin 0.001, set after
    // construction as there (for boxes and cylinders the order sets the inner extents).
    switch (d->type) {
        case SS_GEOM_SPHERE:
            owned.reset(new btSphereShape(d->size[0]));
            owned->setMargin(0.001);
            break;
        case SS_GEOM_BOX:
            owned.reset(new btBoxShape(btVector3(d->size[0], d->size[1], d->size[2])));
            owned->setMargin(0.001);
            break;
        case SS_GEOM_CYLINDER:
            // createCylinderShapeZ(radius, 0.5 * height) is btCylinderShapeZ((radius, radius, 0.5 * height)).
            owned.reset(new btCylinderShapeZ(btVector3(d->size[0], d->size[0], 0.5 * d->size[1])));
            owned->setMargin(0.001);
            break;
        case SS_GEOM_PLANE:
            owned.reset(new btStaticPlaneShape(btVector3(0, 0, 1), 0));
            owned->setMargin(0.001);
            break;
        case SS_GEOM_HEIGHTFIELD: {
            // GEOM_HEIGHTFIELD with heightfieldData (PSCP 4964-5133): the float samples widened to btScalar,
            // their min and max, the legacy constructor with PHY_FLOAT (which is btScalar in a double build),
            // flipped winding for z up, then meshScale as local scaling and the accelerator. No margin set.
            const int width = d->rows;
            const int height = d->columns;
            std::unique_ptr<btScalar[]> data(new btScalar[(size_t)width * (size_t)height]);
            btScalar min_height = d->heights[0];
            btScalar max_height = d->heights[0];
            for (int i = 0; i < width * height; i++) {
                data[i] = d->heights[i];
                min_height = btMin(min_height, data[i]);
                max_height = btMax(max_height, data[i]);
            }
            btScalar grid_height_scale = 1. / 256.;
            bool flip_quad_edges = false;
            int up_axis = 2;
            auto terrain = new btHeightfieldTerrainShape(width, height, data.get(), grid_height_scale, min_height,
                                                         max_height, up_axis, PHY_FLOAT, flip_quad_edges);
            owned.reset(terrain);
            terrain->setUserValue3(1);  // heightfieldTextureScaling's default; drawing only
            terrain->setFlipTriangleWinding(true);
            terrain->setLocalScaling(btVector3(d->size[0], d->size[1], d->size[2]));
            terrain->buildAccelerator();
            w->heightfields.push_back(std::move(data));
            break;
        }
        default:
            return fail(SS_ERR_ARGUMENT, "unknown static shape type");
    }
    btCollisionShape* shape = owned.get();
    w->shapes.push_back(std::move(owned));
    return build_multibody(w, shape, 0.0, d->position, d->orientation, 0, nullptr, nullptr, nullptr, nullptr, nullptr,
                           body_out);
    SS_GUARD_END
}

int ss_world_add_box_chain(ss_world* w, const ss_chain_desc* d, int* body_out) {
    if (!w || !d || !body_out) return fail(SS_ERR_NULL, "null argument");
    if (d->num_links < 0) return fail(SS_ERR_ARGUMENT, "num_links must be >= 0");
    if (d->num_links > 0 && (!d->link_masses || !d->link_positions || !d->link_orientations || !d->link_parents || !d->link_axes))
        return fail(SS_ERR_NULL, "link arrays must not be null");
    if (!finite3(d->half_extents) || !(d->half_extents[0] > 0 && d->half_extents[1] > 0 && d->half_extents[2] > 0))
        return fail(SS_ERR_ARGUMENT, "half extents must be positive and finite");
    if (!std::isfinite(d->base_mass) || d->base_mass < 0) return fail(SS_ERR_ARGUMENT, "base mass must be finite and >= 0");
    if (!finite3(d->base_position) || !std::isfinite(d->base_orientation[3]) || !finite3(d->base_orientation))
        return fail(SS_ERR_ARGUMENT, "base pose must be finite");
    for (int i = 0; i < d->num_links; ++i) {
        if (!std::isfinite(d->link_masses[i]) || d->link_masses[i] < 0) return fail(SS_ERR_ARGUMENT, "link masses must be finite and >= 0");
        if (!finite3(d->link_positions + 3 * i) || !finite3(d->link_axes + 3 * i) || !finite3(d->link_orientations + 4 * i) ||
            !std::isfinite(d->link_orientations[4 * i + 3]))
            return fail(SS_ERR_ARGUMENT, "link frames and axes must be finite");
        if (d->link_parents[i] < 0 || d->link_parents[i] > i) return fail(SS_ERR_ARGUMENT, "link parent must be 0 (base) or an earlier link + 1");
    }
    SS_GUARD_BEGIN
    // createCollisionShape(GEOM_BOX): btBoxShape then setMargin(0.001); the order sets the inner extents.
    auto box = std::unique_ptr<btCollisionShape>(
        new btBoxShape(btVector3(d->half_extents[0], d->half_extents[1], d->half_extents[2])));
    box->setMargin(0.001);
    btCollisionShape* shape = box.get();
    w->shapes.push_back(std::move(box));
    return build_multibody(w, shape, d->base_mass, d->base_position, d->base_orientation, d->num_links, d->link_masses,
                           d->link_positions, d->link_orientations, d->link_parents, d->link_axes, body_out);
    SS_GUARD_END
}

int ss_world_add_urdf(ss_world* w, const ss_urdf_desc* d, int* body_out) {
    if (!w || !d || !body_out) return fail(SS_ERR_NULL, "null argument");
    if (const char* problem = check_urdf(d)) return fail(SS_ERR_ARGUMENT, problem);
    SS_GUARD_BEGIN
    return build_urdf(w, d, body_out);
    SS_GUARD_END
}

int ss_body_num_joints(const ss_world* w, int body, int* count) {
    if (!w || !count) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    *count = mb->getNumLinks();
    return SS_OK;
}

int ss_change_dynamics(ss_world* w, int body, int link, const ss_dynamics* d) {
    if (!w || !d) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (link < -1 || link >= mb->getNumLinks()) return fail(SS_ERR_LINK, "no such link");
    if (d->has_anisotropic_friction && !finite3(d->anisotropic_friction)) return fail(SS_ERR_ARGUMENT, "anisotropic friction must be finite");
    SS_GUARD_BEGIN
    // processChangeDynamicsInfoCommand (PSCP 10656), in its order.
    if (d->linear_damping >= 0) mb->setLinearDamping(d->linear_damping);
    if (d->angular_damping >= 0) mb->setAngularDamping(d->angular_damping);
    btCollisionObject* col = link == -1 ? (btCollisionObject*)mb->getBaseCollider() : (btCollisionObject*)mb->getLinkCollider(link);
    if (link >= 0 && d->joint_damping >= 0) mb->getLink(link).m_jointDamping = d->joint_damping;
    if (col) {
        if (d->lateral_friction >= 0) col->setFriction(d->lateral_friction);
        if (d->spinning_friction >= 0) col->setSpinningFriction(d->spinning_friction);
        if (d->rolling_friction >= 0) col->setRollingFriction(d->rolling_friction);
        if (d->restitution >= 0) col->setRestitution(d->restitution);
        if (d->friction_anchor >= 0) {
            if (d->friction_anchor)
                col->setCollisionFlags(col->getCollisionFlags() | btCollisionObject::CF_HAS_FRICTION_ANCHOR);
            else
                col->setCollisionFlags(col->getCollisionFlags() & ~btCollisionObject::CF_HAS_FRICTION_ANCHOR);
        }
        if (d->has_anisotropic_friction) {
            col->setAnisotropicFriction(
                btVector3(d->anisotropic_friction[0], d->anisotropic_friction[1], d->anisotropic_friction[2]));
        }
    }
    return SS_OK;
    SS_GUARD_END
}

int ss_set_mass(ss_world* w, int body, int link, double mass) {
    if (!w) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (link < -1 || link >= mb->getNumLinks()) return fail(SS_ERR_LINK, "no such link");
    if (!std::isfinite(mass) || !(mass > 0)) return fail(SS_ERR_ARGUMENT, "mass must be finite and > 0");
    double old = link == -1 ? mb->getBaseMass() : mb->getLink(link).m_mass;
    if (!(old > 0)) return fail(SS_ERR_ARGUMENT, "a fixed base or massless link keeps its mass");
    SS_GUARD_BEGIN
    // processChangeDynamicsInfoCommand (PSCP 10656), CHANGE_DYNAMICS_INFO_SET_MASS on a multibody: the
    // mass, then the inertia its collision shape gives that mass (the same call loadURDF and
    // createMultiBody made). The fixed/dynamic switch there cannot happen: old and new masses are > 0.
    btCollisionObject* col = link == -1 ? (btCollisionObject*)mb->getBaseCollider() : (btCollisionObject*)mb->getLinkCollider(link);
    if (link == -1) {
        mb->setBaseMass(mass);
        if (col && col->getCollisionShape()) {
            btVector3 inertia;
            col->getCollisionShape()->calculateLocalInertia(mass, inertia);
            mb->setBaseInertia(inertia);
        }
    } else {
        mb->getLink(link).m_mass = mass;
        if (col && col->getCollisionShape()) {
            btVector3 inertia;
            col->getCollisionShape()->calculateLocalInertia(mass, inertia);
            mb->getLink(link).m_inertiaLocal = inertia;
        }
    }
    return SS_OK;
    SS_GUARD_END
}

int ss_get_dynamics_info(const ss_world* w, int body, int link, double* mass, double* lateral_friction,
                         double* inertia) {
    if (!w || !mass || !lateral_friction || !inertia) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (link < -1 || link >= mb->getNumLinks()) return fail(SS_ERR_LINK, "no such link");
    SS_GUARD_BEGIN
    const btCollisionObject* col = link == -1 ? (const btCollisionObject*)mb->getBaseCollider()
                                              : (const btCollisionObject*)mb->getLinkCollider(link);
    *mass = link == -1 ? mb->getBaseMass() : mb->getLink(link).m_mass;
    btVector3 in = link == -1 ? mb->getBaseInertia() : mb->getLink(link).m_inertiaLocal;
    for (int k = 0; k < 3; ++k) inertia[k] = in[k];
    *lateral_friction = col ? col->getFriction() : 0.0;
    return SS_OK;
    SS_GUARD_END
}

int ss_scale_skin_friction(ss_world* w, int body, int link, double factor, int* had_skin) {
    if (!w || !had_skin) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (link < -1 || link >= mb->getNumLinks()) return fail(SS_ERR_LINK, "no such link");
    if (!std::isfinite(factor) || factor < 0) return fail(SS_ERR_ARGUMENT, "skin friction scale must be finite and >= 0");
    SS_GUARD_BEGIN
    *had_skin = 0;
    btCollisionObject* col = link == -1 ? (btCollisionObject*)mb->getBaseCollider() : (btCollisionObject*)mb->getLinkCollider(link);
    if (!col) return SS_OK;
    int index = col->getUserIndex3();
    if (index >= 0 && index < (int)w->skins.size()) {
        snake_shim::Skin& skin = w->skins[index];
        skin.forward *= factor;
        skin.backward *= factor;
        skin.transverse *= factor;
        *had_skin = 1;
    }
    return SS_OK;
    SS_GUARD_END
}

int ss_set_skin_friction(ss_world* w, int body, int link, double forward, double backward, double transverse,
                         const double* axis) {
    if (!w || !axis) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (link < -1 || link >= mb->getNumLinks()) return fail(SS_ERR_LINK, "no such link");
    for (double mu : {forward, backward, transverse})
        if (!std::isfinite(mu) || mu < 0) return fail(SS_ERR_ARGUMENT, "skin friction coefficients must be finite and >= 0");
    if (!finite3(axis)) return fail(SS_ERR_ARGUMENT, "skin axis must be finite");
    btVector3 a(axis[0], axis[1], axis[2]);
    if (!(a.length2() > 0)) return fail(SS_ERR_ARGUMENT, "skin axis must not be zero");
    SS_GUARD_BEGIN
    btCollisionObject* col = link == -1 ? (btCollisionObject*)mb->getBaseCollider() : (btCollisionObject*)mb->getLinkCollider(link);
    if (!col) return fail(SS_ERR_LINK, "link has no collision shape");
    a.normalize();
    // From the link frame into the collider's (centre-of-mass) frame.
    const std::vector<btMatrix3x3>& bases = w->inertial_bases[body];
    if (!bases.empty()) a = bases[link + 1].transpose() * a;
    Skin skin{forward, backward, transverse, a};
    int index = col->getUserIndex3();
    if (index >= 0 && index < (int)w->skins.size()) {
        w->skins[index] = skin;
    } else {
        col->setUserIndex3((int)w->skins.size());
        w->skins.push_back(skin);
    }
    return SS_OK;
    SS_GUARD_END
}

int ss_set_joint_motor(ss_world* w, int body, int joint, int mode, double target_position, double target_velocity,
                       double force, double kp, double kd, double max_velocity) {
    if (!w) return fail(SS_ERR_NULL, "world is null");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (joint < 0 || joint >= mb->getNumLinks() || !joint_motor(mb, joint)) return fail(SS_ERR_LINK, "no such motorised joint");
    if (!std::isfinite(target_position) || !std::isfinite(target_velocity) || !std::isfinite(force) || !std::isfinite(kp) ||
        !std::isfinite(kd) || std::isnan(max_velocity))
        return fail(SS_ERR_ARGUMENT, "motor arguments must be finite");
    SS_GUARD_BEGIN
    switch (mode) {
        case SS_POSITION_CONTROL:
            set_position_motor(mb, joint, w->dt, target_position, target_velocity, force, kp, kd, max_velocity);
            return SS_OK;
        case SS_VELOCITY_CONTROL: {
            // PSCP 7224-7280.
            btMultiBodyJointMotor* motor = joint_motor(mb, joint);
            motor->setVelocityTarget(target_velocity, kd);
            motor->setPositionTarget(0, 0);
            motor->setRhsClamp(SIMD_INFINITY);
            motor->setMaxAppliedImpulse(force * w->dt);
            return SS_OK;
        }
        case SS_TORQUE_CONTROL:
            mb->addJointTorqueMultiDof(joint, 0, force);
            return SS_OK;
        default:
            return fail(SS_ERR_ARGUMENT, "unknown control mode");
    }
    SS_GUARD_END
}

int ss_set_position_targets(ss_world* w, int body, int count, const double* targets, double force, double kp, double kd) {
    if (!w || (count > 0 && !targets)) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (count < 0 || count > mb->getNumLinks()) return fail(SS_ERR_LINK, "more targets than joints");
    if (!std::isfinite(force) || !std::isfinite(kp) || !std::isfinite(kd)) return fail(SS_ERR_ARGUMENT, "motor arguments must be finite");
    for (int j = 0; j < count; ++j) {
        if (!std::isfinite(targets[j])) return fail(SS_ERR_ARGUMENT, "joint targets must be finite");
        if (!joint_motor(mb, j)) return fail(SS_ERR_LINK, "joint has no motor");
    }
    SS_GUARD_BEGIN
    for (int j = 0; j < count; ++j) set_position_motor(mb, j, w->dt, targets[j], 0.0, force, kp, kd, -1.0);
    return SS_OK;
    SS_GUARD_END
}

int ss_set_position_targets_at(ss_world* w, int body, int count, const int* joints, const double* targets,
                               const double* forces, double kp, double kd, const double* max_velocities) {
    if (!w || (count > 0 && (!joints || !targets || !forces))) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (count < 0) return fail(SS_ERR_ARGUMENT, "negative joint count");
    if (!std::isfinite(kp) || !std::isfinite(kd)) return fail(SS_ERR_ARGUMENT, "motor gains must be finite");
    for (int j = 0; j < count; ++j) {
        if (joints[j] < 0 || joints[j] >= mb->getNumLinks() || !joint_motor(mb, joints[j]))
            return fail(SS_ERR_LINK, "joint has no motor");
        if (!std::isfinite(targets[j]) || !std::isfinite(forces[j]))
            return fail(SS_ERR_ARGUMENT, "joint targets and forces must be finite");
        if (max_velocities && !(std::isfinite(max_velocities[j]) && max_velocities[j] >= 0))
            return fail(SS_ERR_ARGUMENT, "maximum joint velocities must be finite and >= 0");
    }
    SS_GUARD_BEGIN
    // One command for all of them (PSCP 7282): each joint's motor in link order; the order of the joints
    // within the command does not matter, each motor is set once. With max_velocities, this is one
    // setJointMotorControl2 per joint (setJointMotorControlArray has no maxVelocity); each touches its
    // own motor only, so the result is the same.
    for (int j = 0; j < count; ++j) {
        const double max_velocity = max_velocities ? max_velocities[j] : -1.0;
        set_position_motor(mb, joints[j], w->dt, targets[j], 0.0, forces[j], kp, kd, max_velocity);
    }
    return SS_OK;
    SS_GUARD_END
}

int ss_world_step(ss_world* w) {
    if (!w) return fail(SS_ERR_NULL, "world is null");
    SS_GUARD_BEGIN
    // processForwardDynamicsCommand (PSCP 10554): joint damping torques first, then stepSimulation(dt, 0).
    for (auto& b : w->bodies) {
        btMultiBody* mb = b.get();
        for (int l = 0; l < mb->getNumLinks(); ++l) {
            for (int d = 0; d < mb->getLink(l).m_dofCount; ++d) {
                double damping_torque = -mb->getLink(l).m_jointDamping * mb->getJointVelMultiDof(l)[d];
                mb->addJointTorqueMultiDof(l, d, damping_torque);
            }
        }
    }
    w->world->stepSimulation(w->dt, 0);
    return SS_OK;
    SS_GUARD_END
}

int ss_get_base_state(const ss_world* w, int body, ss_base_state* out) {
    if (!w || !out) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    SS_GUARD_BEGIN
    // PSCP 7933-7974: the pose goes through a btTransform, so the quaternion is rebuilt from a matrix.
    btTransform tr;
    tr.setOrigin(mb->getBasePos());
    tr.setRotation(mb->getWorldToBaseRot().inverse());
    btQuaternion q = tr.getRotation();
    for (int k = 0; k < 3; ++k) {
        out->position[k] = tr.getOrigin()[k];
        out->linear_velocity[k] = mb->getBaseVel()[k];
        out->angular_velocity[k] = mb->getBaseOmega()[k];
    }
    for (int k = 0; k < 4; ++k) out->orientation[k] = q[k];
    return SS_OK;
    SS_GUARD_END
}

int ss_get_joint_states(const ss_world* w, int body, int count, double* positions, double* velocities, double* torques) {
    if (!w) return fail(SS_ERR_NULL, "world is null");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (count < 0 || count > mb->getNumLinks()) return fail(SS_ERR_LINK, "more joints asked for than the body has");
    SS_GUARD_BEGIN
    for (int j = 0; j < count; ++j) {
        if (positions) positions[j] = mb->getJointPosMultiDof(j)[0];
        if (velocities) velocities[j] = mb->getJointVelMultiDof(j)[0];
        if (torques) {
            btMultiBodyJointMotor* motor = joint_motor(mb, j);
            torques[j] = motor ? motor->getAppliedImpulse(0) / w->dt : 0.0;
        }
    }
    return SS_OK;
    SS_GUARD_END
}

int ss_get_joint_states_at(const ss_world* w, int body, int count, const int* joints, double* positions,
                           double* velocities, double* torques) {
    if (!w || (count > 0 && !joints)) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (count < 0) return fail(SS_ERR_ARGUMENT, "negative joint count");
    for (int j = 0; j < count; ++j)
        if (joints[j] < 0 || joints[j] >= mb->getNumLinks() || mb->getLink(joints[j]).m_dofCount != 1)
            return fail(SS_ERR_LINK, "no such movable joint");
    SS_GUARD_BEGIN
    for (int j = 0; j < count; ++j) {
        int l = joints[j];
        if (positions) positions[j] = mb->getJointPosMultiDof(l)[0];
        if (velocities) velocities[j] = mb->getJointVelMultiDof(l)[0];
        if (torques) {
            btMultiBodyJointMotor* motor = joint_motor(mb, l);
            torques[j] = motor ? motor->getAppliedImpulse(0) / w->dt : 0.0;
        }
    }
    return SS_OK;
    SS_GUARD_END
}

int ss_get_link_poses(const ss_world* w, int body, int count, double* poses) {
    if (!w || (count > 0 && !poses)) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (count < 0 || count > mb->getNumLinks()) return fail(SS_ERR_LINK, "more links asked for than the body has");
    SS_GUARD_BEGIN
    for (int l = 0; l < count; ++l) {
        const btTransform& tr = mb->getLink(l).m_cachedWorldTransform;
        btQuaternion q = tr.getRotation();
        for (int k = 0; k < 3; ++k) poses[7 * l + k] = tr.getOrigin()[k];
        for (int k = 0; k < 4; ++k) poses[7 * l + 3 + k] = q[k];
    }
    return SS_OK;
    SS_GUARD_END
}

int ss_get_shape_poses(const ss_world* w, int body, int link, double* poses, int capacity, int* count_out) {
    if (!w || !count_out || (capacity > 0 && !poses)) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (link < -1 || link >= mb->getNumLinks()) return fail(SS_ERR_LINK, "no such link");
    SS_GUARD_BEGIN
    const btCollisionObject* col = link == -1 ? (const btCollisionObject*)mb->getBaseCollider()
                                              : (const btCollisionObject*)mb->getLinkCollider(link);
    auto put = [&](int k, const btTransform& tr) {
        if (k >= capacity) return;
        btQuaternion q = tr.getRotation();
        for (int i = 0; i < 3; ++i) poses[7 * k + i] = tr.getOrigin()[i];
        for (int i = 0; i < 4; ++i) poses[7 * k + 3 + i] = q[i];
    };
    int count = 0;
    if (col) {
        const btCollisionShape* shape = col->getCollisionShape();
        if (shape->getShapeType() == COMPOUND_SHAPE_PROXYTYPE) {
            const btCompoundShape* compound = static_cast<const btCompoundShape*>(shape);
            count = compound->getNumChildShapes();
            for (int k = 0; k < count; ++k) put(k, compound->getChildTransform(k));
        } else {
            count = 1;
            put(0, btTransform::getIdentity());
        }
    }
    *count_out = count;
    return SS_OK;
    SS_GUARD_END
}

int ss_get_contacts(const ss_world* w, int body, ss_contact* out, int capacity, int* count_out) {
    if (!w || !count_out || (capacity > 0 && !out)) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    SS_GUARD_BEGIN
    auto body_index = [&](const btMultiBody* m) {
        for (size_t i = 0; i < w->bodies.size(); ++i)
            if (w->bodies[i].get() == m) return (int)i;
        return -1;
    };
    int count = 0;
    btDispatcher* dispatcher = w->world->getDispatcher();
    for (int m = 0; m < dispatcher->getNumManifolds(); ++m) {
        const btPersistentManifold* manifold = dispatcher->getManifoldByIndexInternal(m);
        const btMultiBodyLinkCollider* c0 = btMultiBodyLinkCollider::upcast(manifold->getBody0());
        const btMultiBodyLinkCollider* c1 = btMultiBodyLinkCollider::upcast(manifold->getBody1());
        bool ours0 = c0 && c0->m_multiBody == mb;
        bool ours1 = c1 && c1->m_multiBody == mb;
        if (!ours0 && !ours1) continue;
        const btMultiBodyLinkCollider* self = ours0 ? c0 : c1;
        const btMultiBodyLinkCollider* other = ours0 ? c1 : c0;
        for (int p = 0; p < manifold->getNumContacts(); ++p) {
            const btManifoldPoint& pt = manifold->getContactPoint(p);
            if (count < capacity) {
                ss_contact& c = out[count];
                c.link = self->m_link;
                c.other_body = other ? body_index(other->m_multiBody) : -1;
                c.other_link = other ? other->m_link : -1;
                // normalWorldOnB points from B towards A.
                const btVector3& on_self = ours0 ? pt.m_positionWorldOnA : pt.m_positionWorldOnB;
                const btVector3& on_other = ours0 ? pt.m_positionWorldOnB : pt.m_positionWorldOnA;
                btVector3 normal = ours0 ? pt.m_normalWorldOnB : -pt.m_normalWorldOnB;
                for (int k = 0; k < 3; ++k) {
                    c.position_on_body[k] = on_self[k];
                    c.position_on_other[k] = on_other[k];
                    c.normal_on_other[k] = normal[k];
                }
                c.distance = pt.getDistance();
                c.normal_force = pt.getAppliedImpulse() / w->dt;
            }
            ++count;
        }
    }
    *count_out = count;
    return SS_OK;
    SS_GUARD_END
}


int ss_get_link_velocities(const ss_world* w, int body, int count, double* velocities) {
    if (!w || (count > 0 && !velocities)) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (count < 0 || count > mb->getNumLinks()) return fail(SS_ERR_LINK, "more links asked for than the body has");
    SS_GUARD_BEGIN
    // PSCP's getLinkState with computeLinkVelocity (PSCP 7991, 8093): tree velocities in each link's
    // frame (compTreeLinkVelocities), turned to the world by the link's cached world transform.
    btAlignedObjectArray<btVector3> omega, vel;
    omega.resize(mb->getNumLinks() + 1);
    vel.resize(mb->getNumLinks() + 1);
    mb->compTreeLinkVelocities(&omega[0], &vel[0]);
    for (int l = 0; l < count; ++l) {
        const btMatrix3x3& rot = mb->getLink(l).m_cachedWorldTransform.getBasis();
        btVector3 v = rot * vel[l + 1];
        btVector3 o = rot * omega[l + 1];
        for (int k = 0; k < 3; ++k) {
            velocities[6 * l + k] = v[k];
            velocities[6 * l + 3 + k] = o[k];
        }
    }
    return SS_OK;
    SS_GUARD_END
}

int ss_apply_external_force(ss_world* w, int body, int link, const double force[3], const double position[3]) {
    if (!w || !force || !position) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (link < -1 || link >= mb->getNumLinks()) return fail(SS_ERR_LINK, "no such link");
    if (!finite3(force) || !finite3(position)) return fail(SS_ERR_ARGUMENT, "force and position must be finite");
    SS_GUARD_BEGIN
    // PSCP processApplyExternalForceCommand, WORLD_FRAME: the force at the link's frame origin (its centre
    // of mass) plus the torque of its arm.
    btVector3 f(force[0], force[1], force[2]);
    btVector3 p(position[0], position[1], position[2]);
    if (link == -1) {
        btVector3 arm = p - mb->getBaseWorldTransform().getOrigin();
        mb->addBaseForce(f);
        mb->addBaseTorque(arm.cross(f));
    } else {
        btVector3 arm = p - mb->getLink(link).m_cachedWorldTransform.getOrigin();
        mb->addLinkForce(link, f);
        mb->addLinkTorque(link, arm.cross(f));
    }
    return SS_OK;
    SS_GUARD_END
}

int ss_apply_external_torque(ss_world* w, int body, int link, const double torque[3]) {
    if (!w || !torque) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (link < -1 || link >= mb->getNumLinks()) return fail(SS_ERR_LINK, "no such link");
    if (!finite3(torque)) return fail(SS_ERR_ARGUMENT, "torque must be finite");
    SS_GUARD_BEGIN
    btVector3 t(torque[0], torque[1], torque[2]);
    if (link == -1) {
        mb->addBaseTorque(t);
    } else {
        mb->addLinkTorque(link, t);
    }
    return SS_OK;
    SS_GUARD_END
}

int ss_reset_base_state(ss_world* w, int body, const ss_base_state* s) {
    if (!w || !s) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (!finite3(s->position) || !finite3(s->linear_velocity) || !finite3(s->angular_velocity) ||
        !std::isfinite(s->orientation[0]) || !std::isfinite(s->orientation[1]) ||
        !std::isfinite(s->orientation[2]) || !std::isfinite(s->orientation[3]))
        return fail(SS_ERR_ARGUMENT, "base state must be finite");
    btQuaternion q(s->orientation[0], s->orientation[1], s->orientation[2], s->orientation[3]);
    if (q.length2() < 1e-12) return fail(SS_ERR_ARGUMENT, "base orientation must be a non-zero quaternion");
    SS_GUARD_BEGIN
    // PSCP processInitPoseCommand: position, then the inverse of the rotation as given (pybullet does not
    // normalise it), then the velocities (resetBaseVelocity after resetBasePositionAndOrientation).
    mb->setBasePos(btVector3(s->position[0], s->position[1], s->position[2]));
    mb->setWorldToBaseRot(q.inverse());
    mb->setBaseVel(btVector3(s->linear_velocity[0], s->linear_velocity[1], s->linear_velocity[2]));
    mb->setBaseOmega(btVector3(s->angular_velocity[0], s->angular_velocity[1], s->angular_velocity[2]));
    refresh_transforms(mb);
    return SS_OK;
    SS_GUARD_END
}

int ss_reset_joint_states(ss_world* w, int body, int count, const double* positions, const double* velocities) {
    if (!w || (count > 0 && (!positions || !velocities))) return fail(SS_ERR_NULL, "null argument");
    btMultiBody* mb = w->body(body);
    if (!mb) return fail(SS_ERR_BODY, "no such body");
    if (count < 0 || count > mb->getNumLinks()) return fail(SS_ERR_LINK, "more joints given than the body has");
    for (int j = 0; j < count; ++j) {
        if (!std::isfinite(positions[j]) || !std::isfinite(velocities[j]))
            return fail(SS_ERR_ARGUMENT, "joint positions and velocities must be finite");
    }
    SS_GUARD_BEGIN
    for (int j = 0; j < count; ++j) {
        // Fixed joints have no degree of freedom: pybullet skips them too.
        if (mb->getLink(j).m_dofCount != 1) continue;
        btScalar q = positions[j];
        btScalar qd = velocities[j];
        mb->setJointPosMultiDof(j, &q);
        mb->setJointVelMultiDof(j, &qd);
    }
    refresh_transforms(mb);
    return SS_OK;
    SS_GUARD_END
}

}  // extern "C"
