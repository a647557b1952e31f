// shim_urdf.cpp: URDF robots; see shim_internal.h for the shim's files. Each step names the pybullet
// 3.2.7 code it mirrors; the order of calls is part of the contract, as in snake_shim.cpp.

#include "shim_internal.h"

#include <BulletDynamics/Featherstone/btMultiBodyJointLimitConstraint.h>

#include <cmath>
#include <memory>
#include <vector>

namespace snake_shim {
namespace {

// ---- URDF robots: BulletURDFImporter + ConvertURDF2Bullet (examples/Importers/ImportURDFDemo) ----

// UrdfParser::parseTransform (UrdfParser.cpp 160-232): origin times the global scaling 1, and the rpy
// rotation through its own half-angle quaternion, normalised.
btTransform urdf_transform(const ss_urdf_origin& o) {
    btTransform tr;
    tr.setIdentity();
    btScalar scaling = 1;
    btVector3 vec(o.xyz[0], o.xyz[1], o.xyz[2]);
    tr.setOrigin(vec * scaling);
    if (o.has_rpy) {
        double phi = o.rpy[0] / 2.0;
        double the = o.rpy[1] / 2.0;
        double psi = o.rpy[2] / 2.0;
        btQuaternion orn(sin(phi) * cos(the) * cos(psi) - cos(phi) * sin(the) * sin(psi),
                         cos(phi) * sin(the) * cos(psi) + sin(phi) * cos(the) * sin(psi),
                         cos(phi) * cos(the) * sin(psi) - sin(phi) * sin(the) * cos(psi),
                         cos(phi) * cos(the) * cos(psi) + sin(phi) * sin(the) * sin(psi));
        orn.normalize();
        tr.setRotation(orn);
    }
    return tr;
}

// BulletURDFImporter::getMassAndInertia2 (BUI 374-411) and, with URDF_USE_INERTIA_FROM_FILE,
// getMassAndInertia (BUI 413-483).
void urdf_mass_and_inertia(const ss_urdf_link& link, bool from_file, btScalar& mass, btVector3& inertia,
                           btTransform& frame) {
    btTransform local = urdf_transform(link.inertial_origin);
    mass = link.mass;
    if (!from_file) {
        inertia.setValue(0, 0, 0);
        frame.setOrigin(local.getOrigin());
        frame.setBasis(local.getBasis());
        return;
    }
    const double* I = link.inertia;  // ixx, ixy, ixz, iyy, iyz, izz
    btMatrix3x3 basis;
    btScalar px, py, pz;
    if (I[1] == 0.0 && I[2] == 0.0 && I[4] == 0.0) {
        px = I[0];
        py = I[3];
        pz = I[5];
        basis.setIdentity();
    } else {
        btMatrix3x3 tensor(I[0], I[1], I[2], I[1], I[3], I[4], I[2], I[4], I[5]);
        btScalar threshold = 1.0e-6;
        int iterations = 30;
        tensor.diagonalize(basis, threshold, iterations);
        px = tensor[0][0];
        py = tensor[1][1];
        pz = tensor[2][2];
    }
    if (px < 0 || px > (py + pz) || py < 0 || py > (px + pz) || pz < 0 || pz > (px + py)) {
        // "Bad inertia tensor properties, setting inertia to zero".
        px = py = pz = 0;
        basis.setIdentity();
    }
    inertia.setValue(px, py, pz);
    frame.setOrigin(local.getOrigin());
    frame.setBasis(local.getBasis() * basis);
}

// BulletURDFImporter::convertURDFToCollisionShape (BUI 610-700) for the primitive shapes, with default
// flags (no URDF_USE_IMPLICIT_CYLINDER, no SAT features) and the default margin 0.001.
btCollisionShape* urdf_shape(const ss_urdf_shape& s) {
    const btScalar margin = 0.001;
    switch (s.type) {
        case SS_SHAPE_CAPSULE: {
            btScalar radius = s.size[0];
            btScalar height = s.size[1];
            btCollisionShape* shape = new btCapsuleShapeZ(radius, height);
            shape->setMargin(margin);
            return shape;
        }
        case SS_SHAPE_CYLINDER: {
            btScalar radius = s.size[0];
            btScalar half_length = 0.5 * s.size[1];
            btAlignedObjectArray<btVector3> vertices;
            int num_steps = 32;
            for (int i = 0; i < num_steps; i++) {
                // The angle is computed in float, as the importer does.
                btVector3 vert(radius * btSin(SIMD_2_PI * (float(i) / num_steps)),
                               radius * btCos(SIMD_2_PI * (float(i) / num_steps)), half_length);
                vertices.push_back(vert);
                vert[2] = -half_length;
                vertices.push_back(vert);
            }
            btConvexHullShape* hull = new btConvexHullShape(&vertices[0].x(), vertices.size(), sizeof(btVector3));
            hull->setMargin(margin);
            hull->recalcLocalAabb();
            hull->optimizeConvexHull();
            return hull;
        }
        case SS_SHAPE_BOX: {
            btVector3 extents(s.size[0], s.size[1], s.size[2]);
            btCollisionShape* shape = new btBoxShape(extents * 0.5f);
            shape->setMargin(margin);
            return shape;
        }
        case SS_SHAPE_SPHERE: {
            btScalar radius = s.size[0];
            btCollisionShape* shape = new btSphereShape(radius);
            shape->setMargin(margin);
            return shape;
        }
        default:
            return nullptr;
    }
}

// processContactParameters (U2B 171-197).
void urdf_contact(const ss_urdf_contact& c, btCollisionObject* col) {
    col->setFriction(c.lateral_friction);  // URDF_CONTACT_HAS_LATERAL_FRICTION is always set
    if (c.flags & SS_CONTACT_RESTITUTION) col->setRestitution(c.restitution);
    if (c.flags & SS_CONTACT_ROLLING_FRICTION) col->setRollingFriction(c.rolling_friction);
    if (c.flags & SS_CONTACT_SPINNING_FRICTION) col->setSpinningFriction(c.spinning_friction);
    if (c.flags & SS_CONTACT_STIFFNESS_DAMPING) col->setContactStiffnessAndDamping(c.stiffness, c.damping);
    if (c.flags & SS_CONTACT_FRICTION_ANCHOR)
        col->setCollisionFlags(col->getCollisionFlags() | btCollisionObject::CF_HAS_FRICTION_ANCHOR);
}

bool finite_origin(const ss_urdf_origin& o) { return finite3(o.xyz) && finite3(o.rpy); }

}  // namespace

const char* check_urdf(const ss_urdf_desc* d) {
    if (d->num_links < 1) return "a robot needs at least its root link";
    if (!d->links) return "links must not be null";
    if (!finite3(d->base_position) || !finite3(d->base_orientation) || !std::isfinite(d->base_orientation[3]))
        return "base pose must be finite";
    for (int i = 0; i < d->num_links; ++i) {
        const ss_urdf_link& l = d->links[i];
        if (i == 0 ? l.parent != -1 : (l.parent < 0 || l.parent >= i))
            return "links must be in depth-first order from the root (each parent before its children)";
        if (!std::isfinite(l.mass) || !finite_origin(l.inertial_origin) || !finite_origin(l.joint_origin) ||
            !finite3(l.axis) || !finite3(l.inertia) || !finite3(l.inertia + 3))
            return "link values must be finite";
        if (l.num_shapes < 0 || (l.num_shapes > 0 && !l.shapes)) return "shapes must not be null";
        for (int s = 0; s < l.num_shapes; ++s) {
            const ss_urdf_shape& sh = l.shapes[s];
            if (sh.type < SS_SHAPE_BOX || sh.type > SS_SHAPE_CAPSULE) return "unknown shape type";
            if (!finite3(sh.size) || !finite_origin(sh.origin)) return "shape values must be finite";
        }
        if (i > 0 && l.joint_type != SS_JOINT_REVOLUTE && l.joint_type != SS_JOINT_PRISMATIC &&
            l.joint_type != SS_JOINT_CONTINUOUS && l.joint_type != SS_JOINT_FIXED)
            return "unknown joint type";
    }
    return nullptr;
}

// ConvertURDF2Bullet (U2B 811-895) with ConvertURDF2BulletInternal (U2B 202-768) for each link in depth-first
// order, then createJointMotors (PSCP 3117).
int build_urdf(ss_world* w, const ss_urdf_desc* d, int* body_out) {
    const bool from_file = d->inertia_from_file != 0;
    const int n = d->num_links;
    btTransform root;
    root.setOrigin(btVector3(d->base_position[0], d->base_position[1], d->base_position[2]));
    root.setRotation(btQuaternion(d->base_orientation[0], d->base_orientation[1], d->base_orientation[2],
                                  d->base_orientation[3]));

    std::unique_ptr<btMultiBody> owned;
    btMultiBody* body = nullptr;
    std::vector<btTransform> link_world(n);
    std::vector<btTransform> inertial_frames(n);
    std::vector<std::unique_ptr<btMultiBodyConstraint>> limits;

    for (int i = 0; i < n; ++i) {
        const ss_urdf_link& link = d->links[i];
        const int mb_index = i - 1;
        const int mb_parent = link.parent - 1;

        btTransform parent_inertial;
        parent_inertial.setIdentity();
        if (link.parent >= 0) {
            btScalar parent_mass;
            btVector3 parent_inertia;
            urdf_mass_and_inertia(d->links[link.parent], from_file, parent_mass, parent_inertia, parent_inertial);
        }
        btScalar mass = 0;
        btTransform local_inertial;
        local_inertial.setIdentity();
        btVector3 inertia(0, 0, 0);
        urdf_mass_and_inertia(link, from_file, mass, inertia, local_inertial);
        inertial_frames[i] = local_inertial;

        btTransform parent2joint;
        parent2joint.setIdentity();
        if (i > 0) parent2joint = urdf_transform(link.joint_origin);
        link_world[i] = (i == 0 ? root : link_world[link.parent]) * parent2joint;

        // convertLinkCollisionShapes (BUI 1498): a compound of every collision shape relative to the
        // inertial frame, unwrapped when it holds one child at exactly the identity.
        btCompoundShape* compound = new btCompoundShape();
        w->shapes.push_back(std::unique_ptr<btCollisionShape>(compound));
        compound->setMargin(0.001);
        for (int s = 0; s < link.num_shapes; ++s) {
            btCollisionShape* child = urdf_shape(link.shapes[s]);
            if (!child) return fail(SS_ERR_ARGUMENT, "unknown shape type");
            w->shapes.push_back(std::unique_ptr<btCollisionShape>(child));
            btTransform child_tr = urdf_transform(link.shapes[s].origin);
            compound->addChildShape(local_inertial.inverse() * child_tr, child);
        }
        btCollisionShape* shape = compound;
        if (compound->getNumChildShapes() == 1 && compound->getChildTransform(0) == btTransform::getIdentity())
            shape = compound->getChildShape(0);

        if (mass) {
            if (!from_file) shape->calculateLocalInertia(mass, inertia);
            if (link.contact.flags & SS_CONTACT_INERTIA_SCALING) inertia *= link.contact.inertia_scaling;
        }

        if (i == 0) {
            bool fixed_base = (mass == 0);
            owned.reset(new btMultiBody(n - 1, mass, inertia, fixed_base, false));
            body = owned.get();
        } else {
            btTransform offset_in_a = parent_inertial.inverse() * parent2joint;
            btTransform offset_in_b = local_inertial.inverse();
            btQuaternion parent_rot_to_this = offset_in_b.getRotation() * offset_in_a.inverse().getRotation();
            btMultibodyLink& l = body->getLink(mb_index);
            l.m_jointDamping = link.damping;
            l.m_jointFriction = link.friction;
            l.m_jointLowerLimit = link.lower;
            l.m_jointUpperLimit = link.upper;
            l.m_jointMaxForce = link.effort;
            l.m_jointMaxVelocity = link.velocity;
            btVector3 axis(link.axis[0], link.axis[1], link.axis[2]);
            switch (link.joint_type) {
                case SS_JOINT_FIXED:
                    body->setupFixed(mb_index, mass, inertia, mb_parent, parent_rot_to_this, offset_in_a.getOrigin(),
                                     -offset_in_b.getOrigin());
                    break;
                case SS_JOINT_CONTINUOUS:
                case SS_JOINT_REVOLUTE:
                    body->setupRevolute(mb_index, mass, inertia, mb_parent, parent_rot_to_this,
                                        quatRotate(offset_in_b.getRotation(), axis), offset_in_a.getOrigin(),
                                        -offset_in_b.getOrigin(), true);
                    if (link.joint_type == SS_JOINT_REVOLUTE && link.lower <= link.upper) {
                        limits.emplace_back(new btMultiBodyJointLimitConstraint(body, mb_index, link.lower, link.upper));
                        w->world->addMultiBodyConstraint(limits.back().get());
                    }
                    break;
                case SS_JOINT_PRISMATIC:
                    body->setupPrismatic(mb_index, mass, inertia, mb_parent, parent_rot_to_this,
                                         quatRotate(offset_in_b.getRotation(), axis), offset_in_a.getOrigin(),
                                         -offset_in_b.getOrigin(), true);
                    if (link.lower <= link.upper) {
                        limits.emplace_back(new btMultiBodyJointLimitConstraint(body, mb_index, link.lower, link.upper));
                        w->world->addMultiBodyConstraint(limits.back().get());
                    }
                    break;
                default:
                    return fail(SS_ERR_ARGUMENT, "unknown joint type");
            }
        }

        // The link's collider, in the link frame for now (U2B 626-731).
        auto col = std::unique_ptr<btMultiBodyLinkCollider>(new btMultiBodyLinkCollider(body, mb_index));
        col->setCollisionShape(shape);
        col->setWorldTransform(link_world[i]);
        bool dynamic = !(mb_index < 0 && body->hasFixedBase());
        int group = dynamic ? int(btBroadphaseProxy::DefaultFilter) : int(btBroadphaseProxy::StaticFilter);
        int mask = dynamic ? int(btBroadphaseProxy::AllFilter) : int(btBroadphaseProxy::AllFilter ^ btBroadphaseProxy::StaticFilter);
        if (link.has_collision_group) group = link.collision_group;
        if (link.has_collision_mask) mask = link.collision_mask;
        w->world->addCollisionObject(col.get(), group, mask);
        urdf_contact(link.contact, col.get());
        if (mb_index >= 0) {
            if (body->getBaseMass() == 0) {
                // As U2B 707-720 writes it: the walk stops before checking link 0 unless it starts there.
                bool all_fixed = true;
                int test = mb_index;
                do {
                    if (body->getLink(test).m_jointType != btMultibodyLink::eFixed) {
                        all_fixed = false;
                        break;
                    }
                    test = body->getLink(test).m_parent;
                } while (test > 0);
                if (all_fixed) col->setCollisionFlags(col->getCollisionFlags() | btCollisionObject::CF_STATIC_OBJECT);
            }
            body->getLink(mb_index).m_collider = col.get();
        } else {
            if (body->getBaseMass() == 0)
                col->setCollisionFlags(col->getCollisionFlags() | btCollisionObject::CF_STATIC_OBJECT);
            body->setBaseCollider(col.get());
        }
        w->colliders.push_back(std::move(col));
    }

    // Post process (U2B 868-895).
    body->setHasSelfCollision(false);
    body->finalizeMultiDof();
    body->setBaseWorldTransform(root * inertial_frames[0]);
    btAlignedObjectArray<btQuaternion> scratch_q;
    btAlignedObjectArray<btVector3> scratch_m;
    body->forwardKinematics(scratch_q, scratch_m);
    body->updateCollisionObjectWorldTransforms(scratch_q, scratch_m);
    w->world->addMultiBody(body);
    for (auto& c : limits) w->constraints.push_back(std::move(c));

    // createJointMotors (PSCP 3117).
    add_default_motors(w, body);

    *body_out = (int)w->bodies.size();
    w->bodies.push_back(std::move(owned));
    std::vector<btMatrix3x3> bases;
    for (const btTransform& tr : inertial_frames) bases.push_back(tr.getBasis());
    w->inertial_bases.push_back(std::move(bases));
    return SS_OK;
}

}  // namespace snake_shim
