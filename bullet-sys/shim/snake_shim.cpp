// snake_shim.cpp: see snake_shim.h. Each step below names the pybullet 3.2.7 code it mirrors; the order
// of calls is part of the contract, because pair order, proxy ids and rounding all follow from it.

#include "snake_shim.h"

#include <btBulletDynamicsCommon.h>
#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyJointLimitConstraint.h>
#include <BulletDynamics/Featherstone/btMultiBodyJointMotor.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
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

namespace {

thread_local std::string g_last_error;

int fail(int code, const char* message) {
    g_last_error = message;
    return code;
}

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

// pybullet's MyOverlapFilterCallback in B3_FILTER_GROUPAMASKB_OR_GROUPBMASKA mode (PSCP 781-852).
struct OrFilterCallback : public btOverlapFilterCallback {
    bool needBroadphaseCollision(btBroadphaseProxy* p0, btBroadphaseProxy* p1) const override {
        bool collides = (p0->m_collisionFilterGroup & p1->m_collisionFilterMask) != 0;
        collides = collides || (p1->m_collisionFilterGroup & p0->m_collisionFilterMask);
        return collides;
    }
};

bool finite3(const double* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

// ---- Skin friction (issue 27): Hu et al.'s forward/backward/transverse law inside the contact solver ----
//
// Bullet builds two friction rows per contact (directions btPlaneSpace1 of the normal) and clamps their
// pair against a circular cone each iteration. For a contact of a link with skin friction, SkinSolver
// takes that pair out of Bullet's friction array after Bullet's setup, rebuilds its two rows along
// t (the skin axis projected into the contact plane) and n (in the plane, normal to t), and solves them
// after Bullet's own rows in every iteration with the law's force set (see solve_skin_contact). Before
// Bullet's finish the pairs go back into its array, so that the write-back (constraint forces, the
// contact point's lateral impulses) sees them as ordinary rows. A solve with no skin contact makes
// exactly Bullet's calls in Bullet's order: worlds without skin friction keep pybullet parity.

struct Skin {
    double forward, backward, transverse;
    btVector3 axis;  // unit, in the collider's (centre-of-mass) frame
};

class SkinSolver : public btMultiBodyConstraintSolver {
public:
    explicit SkinSolver(const std::vector<Skin>* skins) : m_skins(skins) {}

protected:
    // One skin contact: its normal row and its coefficients, already combined with the other object's
    // friction. Its two friction rows are m_skinRows[2k] (along t) and [2k + 1] (along n).
    struct SkinContact {
        int normal;
        btScalar forward, backward, transverse;
        // 1 / m_jacDiagABInv of the t and n rows (0 for a disabled row): the solve multiplies by these
        // rather than dividing, as divisions were its hottest instructions.
        btScalar kt, kn;
        // The sliding solve's root from the previous iteration: it starts Newton's method there.
        btScalar s;
    };
    const std::vector<Skin>* m_skins;
    btAlignedObjectArray<btMultiBodySolverConstraint> m_skinRows;
    std::vector<SkinContact> m_skinContacts;

    const Skin* skin_of(const btMultiBody* mb, int link, const btCollisionObject** col_out) const {
        if (!mb) return nullptr;
        const btCollisionObject* col =
            link < 0 ? (const btCollisionObject*)mb->getBaseCollider() : (const btCollisionObject*)mb->getLinkCollider(link);
        *col_out = col;
        if (!col) return nullptr;
        int index = col->getUserIndex3();
        if (index < 0 || index >= (int)m_skins->size()) return nullptr;
        return &(*m_skins)[index];
    }

    // The lateral friction of the object on side A (b = false) or B (true) of a row.
    btScalar side_friction(const btMultiBodySolverConstraint& c, bool b) const {
        const btMultiBody* mb = b ? c.m_multiBodyB : c.m_multiBodyA;
        int link = b ? c.m_linkB : c.m_linkA;
        if (mb) {
            const btCollisionObject* col = link < 0 ? (const btCollisionObject*)mb->getBaseCollider()
                                                    : (const btCollisionObject*)mb->getLinkCollider(link);
            return col ? col->getFriction() : btScalar(1);
        }
        int id = b ? c.m_solverBodyIdB : c.m_solverBodyIdA;
        if (id >= 0 && m_tmpSolverBodyPool[id].m_originalBody) return m_tmpSolverBodyPool[id].m_originalBody->getFriction();
        return btScalar(1);
    }

    btScalar solveGroupCacheFriendlySetup(btCollisionObject** bodies, int numBodies, btPersistentManifold** manifolds,
                                          int numManifolds, btTypedConstraint** constraints, int numConstraints,
                                          const btContactSolverInfo& info, btIDebugDraw* debug) override {
        btScalar result = btMultiBodyConstraintSolver::solveGroupCacheFriendlySetup(
            bodies, numBodies, manifolds, numManifolds, constraints, numConstraints, info, debug);
        m_skinRows.resize(0);
        m_skinContacts.clear();
        if (m_skins->empty()) return result;
        // The pairing below needs Bullet's two friction rows per contact in the cone mode pybullet uses.
        if (!(info.m_solverMode & SOLVER_USE_2_FRICTION_DIRECTIONS) || (info.m_solverMode & SOLVER_DISABLE_IMPLICIT_CONE_FRICTION))
            return result;
        btMultiBodyConstraintArray& friction = m_multiBodyFrictionContactConstraints;
        int write = 0;
        for (int i = 0; i < m_multiBodyNormalContactConstraints.size(); ++i) {
            btMultiBodySolverConstraint& normal = m_multiBodyNormalContactConstraints[i];
            const int f = normal.m_frictionIndex;
            const btMultiBodySolverConstraint& row = friction[f];
            const btCollisionObject* col = nullptr;
            const Skin* skin = skin_of(row.m_multiBodyA, row.m_linkA, &col);
            btScalar side = 1;  // +1: the skin link is body A of the rows
            if (!skin) {
                skin = skin_of(row.m_multiBodyB, row.m_linkB, &col);
                side = -1;
            }
            if (!skin) {
                // Not a skin contact: the pair moves down to close the gaps, in Bullet's order.
                if (write != f) {
                    friction[write] = friction[f];
                    friction[write + 1] = friction[f + 1];
                }
                normal.m_frictionIndex = write;
                write += 2;
                continue;
            }
            btManifoldPoint& cp = *(btManifoldPoint*)row.m_originalContactPoint;
            const btScalar other = side_friction(row, side > 0);
            auto combine = [&](double mu) { return btMin(btScalar(mu) * other, btScalar(10)); };
            SkinContact sc{i, combine(skin->forward), combine(skin->backward), combine(skin->transverse), 0, 0, 0};
            m_skinRows.push_back(friction[f]);
            m_skinRows.push_back(friction[f + 1]);
            btMultiBodySolverConstraint& rt = m_skinRows[m_skinRows.size() - 2];
            btMultiBodySolverConstraint& rn = m_skinRows[m_skinRows.size() - 1];
            const btVector3& normal_dir = cp.m_normalWorldOnB;
            btVector3 axis = col->getWorldTransform().getBasis() * skin->axis;
            btVector3 t = axis - normal_dir * axis.dot(normal_dir);
            // |t| is the sine of the angle between the skin axis and the contact normal. Where the axis
            // leaves the contact plane, the forward/backward coefficients blend into the transverse one in
            // proportion to it: the law as written (t normalised) would switch between them at random
            // when the axis is normal to the plane, where every in-plane direction is transverse. For a
            // link lying on the ground |t| is 1 and the law holds as written.
            const btScalar w = btMin(t.length(), btScalar(1));
            sc.forward = sc.transverse + (sc.forward - sc.transverse) * w;
            sc.backward = sc.transverse + (sc.backward - sc.transverse) * w;
            if (!(w > btScalar(1e-9))) {
                btVector3 other_dir;
                btPlaneSpace1(normal_dir, t, other_dir);
            }
            // Rows along side * t and the normal to it: a positive impulse is then a force on the skin link
            // along +t (or +n), and the row's velocity is the skin's sliding velocity along it.
            t.normalize();
            const btVector3 dt = t * side;
            const btVector3 dn = normal_dir.cross(dt);
            if (!rotate_pair(rt, rn, normal, dt, dn, cp, info)) {
                btScalar relaxation;
                const btScalar zero = 0;
                setupMultiBodyContactConstraint(rt, dt, zero, cp, info, relaxation, true);
                setupMultiBodyContactConstraint(rn, dn, zero, cp, info, relaxation, true);
            }
            // The contact reports its friction along the directions its impulses act in.
            cp.m_lateralFrictionDir1 = dt;
            cp.m_lateralFrictionDir2 = dn;
            sc.kt = rt.m_jacDiagABInv > 0 ? 1 / rt.m_jacDiagABInv : btScalar(0);
            sc.kn = rn.m_jacDiagABInv > 0 ? 1 / rn.m_jacDiagABInv : btScalar(0);
            m_skinContacts.push_back(sc);
            normal.m_frictionIndex = -1;
        }
        friction.resize(write);
        return result;
    }

    // Turns Bullet's friction pair r1, r2 of a contact (normal row nrm) into rows along dt and dn. A row's
    // Jacobian and its unit-impulse velocity change (M^-1 J^T) are linear in its direction, and the three
    // rows of a contact share its points and bodies, so the new ones are combinations of Bullet's: this replaces
    // a second Jacobian fill and articulated-body solve per row (calcAccelerationDeltasMultiDof, the
    // setup's dearest part) with a few multiply-adds. The rest is setupMultiBodyContactConstraint's
    // friction-row arithmetic: effective mass with the friction CFM and SOR, right-hand side -v J^-1.
    // Returns false, leaving the rows alone, where that arithmetic would not be the whole setup: a side
    // that is a rigid body rather than a multibody, a friction anchor (a positional term), articulated
    // warm starting (an initial impulse).
    bool rotate_pair(btMultiBodySolverConstraint& r1, btMultiBodySolverConstraint& r2, const btMultiBodySolverConstraint& nrm, const btVector3& dt,
                     const btVector3& dn, const btManifoldPoint& cp, const btContactSolverInfo& info) {
        if (!r1.m_multiBodyA || !r1.m_multiBodyB) return false;
        if (cp.m_contactPointFlags & BT_CONTACT_FLAG_FRICTION_ANCHOR) return false;
        if (info.m_solverMode & SOLVER_USE_ARTICULATED_WARMSTARTING) return false;
        // d1, d2 need not be orthonormal, nor even in the contact plane: Bullet scales them in the link's
        // frame by its anisotropic friction, which tilts them out of the plane when the link tilts. With
        // the normal row's direction they still span space, so d = c1 d1 + c2 d2 + c3 m for d = dt, dn
        // (Cramer's rule). A (nearly) degenerate basis, as a zero anisotropic coefficient makes, is left
        // to the full setup.
        const btVector3 d1 = r1.m_contactNormal1, d2 = r2.m_contactNormal1, m = nrm.m_contactNormal1;
        const btVector3 x23 = d2.cross(m), x31 = m.cross(d1), x12 = d1.cross(d2);
        const btScalar det = d1.dot(x23);
        if (!(btFabs(det) > btScalar(1e-6) * d1.length() * d2.length() * m.length())) return false;
        const btScalar inv_det = 1 / det;
        const btScalar c11 = dt.dot(x23) * inv_det, c12 = dt.dot(x31) * inv_det, c13 = dt.dot(x12) * inv_det;
        const btScalar c21 = dn.dot(x23) * inv_det, c22 = dn.dot(x31) * inv_det, c23 = dn.dot(x12) * inv_det;
        btScalar denom1 = 0, denom2 = 0, vel1 = 0, vel2 = 0;
        for (int side = 0; side < 2; ++side) {
            btMultiBody* mb = side ? r1.m_multiBodyB : r1.m_multiBodyA;
            const int n = mb->getNumDofs() + 6;
            btScalar* j1 = &m_data.m_jacobians[side ? r1.m_jacBindex : r1.m_jacAindex];
            btScalar* j2 = &m_data.m_jacobians[side ? r2.m_jacBindex : r2.m_jacAindex];
            btScalar* u1 = &m_data.m_deltaVelocitiesUnitImpulse[side ? r1.m_jacBindex : r1.m_jacAindex];
            btScalar* u2 = &m_data.m_deltaVelocitiesUnitImpulse[side ? r2.m_jacBindex : r2.m_jacAindex];
            const btScalar* j3 = &m_data.m_jacobians[side ? nrm.m_jacBindex : nrm.m_jacAindex];
            const btScalar* u3 = &m_data.m_deltaVelocitiesUnitImpulse[side ? nrm.m_jacBindex : nrm.m_jacAindex];
            const btScalar* v = mb->getVelocityVector();
            for (int i = 0; i < n; ++i) {
                const btScalar a = j1[i], b = j2[i], c = j3[i];
                j1[i] = c11 * a + c12 * b + c13 * c;
                j2[i] = c21 * a + c22 * b + c23 * c;
                const btScalar p = u1[i], q = u2[i], r = u3[i];
                u1[i] = c11 * p + c12 * q + c13 * r;
                u2[i] = c21 * p + c22 * q + c23 * r;
                denom1 += j1[i] * u1[i];
                denom2 += j2[i] * u2[i];
                vel1 += v[i] * j1[i];
                vel2 += v[i] * j2[i];
            }
        }
        const btScalar cfm = info.m_frictionCFM * (btScalar(1) / info.m_timeStep);
        auto finish = [&](btMultiBodySolverConstraint& r, const btVector3& d, btScalar denom, btScalar vel) {
            r.m_contactNormal1 = d;
            r.m_contactNormal2 = -d;
            const btScalar dd = denom + cfm;
            r.m_jacDiagABInv = dd > SIMD_EPSILON ? info.m_sor / dd : btScalar(0);
            r.m_rhs = -vel * r.m_jacDiagABInv;
            r.m_rhsPenetration = 0;
            r.m_cfm = cfm * r.m_jacDiagABInv;
            r.m_appliedImpulse = 0;
            r.m_appliedPushImpulse = 0;
        };
        // The cross products with the lever arms are linear in the direction too.
        const btVector3 a1 = r1.m_relpos1CrossNormal, a2 = r2.m_relpos1CrossNormal, a3 = nrm.m_relpos1CrossNormal;
        const btVector3 b1 = r1.m_relpos2CrossNormal, b2 = r2.m_relpos2CrossNormal, b3 = nrm.m_relpos2CrossNormal;
        r1.m_relpos1CrossNormal = a1 * c11 + a2 * c12 + a3 * c13;
        r2.m_relpos1CrossNormal = a1 * c21 + a2 * c22 + a3 * c23;
        r1.m_relpos2CrossNormal = b1 * c11 + b2 * c12 + b3 * c13;
        r2.m_relpos2CrossNormal = b1 * c21 + b2 * c22 + b3 * c23;
        finish(r1, dt, denom1, vel1);
        finish(r2, dn, denom2, vel2);
        return true;
    }

    // Velocity along row c produced by the impulses applied so far in this solve.
    btScalar row_delta_velocity(const btMultiBodySolverConstraint& c) {
        btScalar v = 0;
        if (c.m_multiBodyA) {
            const int n = c.m_multiBodyA->getNumDofs() + 6;
            for (int i = 0; i < n; ++i) v += m_data.m_jacobians[c.m_jacAindex + i] * m_data.m_deltaVelocities[c.m_deltaVelAindex + i];
        } else if (c.m_solverBodyIdA >= 0) {
            btSolverBody& b = m_tmpSolverBodyPool[c.m_solverBodyIdA];
            v += c.m_contactNormal1.dot(b.internalGetDeltaLinearVelocity()) + c.m_relpos1CrossNormal.dot(b.internalGetDeltaAngularVelocity());
        }
        if (c.m_multiBodyB) {
            const int n = c.m_multiBodyB->getNumDofs() + 6;
            for (int i = 0; i < n; ++i) v += m_data.m_jacobians[c.m_jacBindex + i] * m_data.m_deltaVelocities[c.m_deltaVelBindex + i];
        } else if (c.m_solverBodyIdB >= 0) {
            btSolverBody& b = m_tmpSolverBodyPool[c.m_solverBodyIdB];
            v += c.m_contactNormal2.dot(b.internalGetDeltaLinearVelocity()) + c.m_relpos2CrossNormal.dot(b.internalGetDeltaAngularVelocity());
        }
        return v;
    }

    void apply_row_impulse(const btMultiBodySolverConstraint& c, btScalar impulse) {
        if (c.m_multiBodyA) {
            const int n = c.m_multiBodyA->getNumDofs() + 6;
            applyDeltaVee(&m_data.m_deltaVelocitiesUnitImpulse[c.m_jacAindex], impulse, c.m_deltaVelAindex, n);
            c.m_multiBodyA->applyDeltaVeeMultiDof2(&m_data.m_deltaVelocitiesUnitImpulse[c.m_jacAindex], impulse);
            c.m_multiBodyA->setPosUpdated(false);
        } else if (c.m_solverBodyIdA >= 0) {
            btSolverBody& b = m_tmpSolverBodyPool[c.m_solverBodyIdA];
            b.internalApplyImpulse(c.m_contactNormal1 * b.internalGetInvMass(), c.m_angularComponentA, impulse);
        }
        if (c.m_multiBodyB) {
            const int n = c.m_multiBodyB->getNumDofs() + 6;
            applyDeltaVee(&m_data.m_deltaVelocitiesUnitImpulse[c.m_jacBindex], impulse, c.m_deltaVelBindex, n);
            c.m_multiBodyB->applyDeltaVeeMultiDof2(&m_data.m_deltaVelocitiesUnitImpulse[c.m_jacBindex], impulse);
            c.m_multiBodyB->setPosUpdated(false);
        } else if (c.m_solverBodyIdB >= 0) {
            btSolverBody& b = m_tmpSolverBodyPool[c.m_solverBodyIdB];
            b.internalApplyImpulse(c.m_contactNormal2 * b.internalGetInvMass(), c.m_angularComponentB, impulse);
        }
    }

    // The friction impulse of one skin contact for this iteration. With st, sn the impulses (force on the
    // skin link along t and n) that would stop the contact, each with its row's own effective mass as
    // Bullet's rows use it:
    // - sticking, when (st, sn) lies in the law's force set (the half ellipse (st / (mu_f N))^2 +
    //   (sn / (mu_t N))^2 <= 1 for st <= 0, with mu_b for st > 0): the impulse is (st, sn);
    // - sliding otherwise: the impulse -N (mu_a u_t, mu_t u_n) of the law at the sliding direction u that
    //   it itself produces, u = K (impulse - (st, sn)) / |...| with K the rows' inverse effective masses.
    //   Writing u_i = -a_i / (s + b_i) (a_i = K_i s_i, b_i = K_i mu_i N) turns that into one equation,
    //   sum_i (a_i / (s + b_i))^2 = 1 for s >= 0, convex and decreasing in s, which Newton's method solves
    //   from the previous iteration's root (a contact's root moves little between iterations, so two or
    //   three steps usually do). The result is continuous at the stick/slip boundary, equals Coulomb's clamp when the
    //   contact slides along t or n, and Bullet's cone clamp when the skin is isotropic and the two rows
    //   have equal effective masses.
    btScalar solve_skin_contact(int k) {
        btMultiBodySolverConstraint& rt = m_skinRows[2 * k];
        btMultiBodySolverConstraint& rn = m_skinRows[2 * k + 1];
        SkinContact& sc = m_skinContacts[k];
        const btScalar N = m_multiBodyNormalContactConstraints[sc.normal].m_appliedImpulse;
        const btScalar st = rt.m_appliedImpulse + rt.m_rhs - rt.m_appliedImpulse * rt.m_cfm - row_delta_velocity(rt) * rt.m_jacDiagABInv;
        const btScalar sn = rn.m_appliedImpulse + rn.m_rhs - rn.m_appliedImpulse * rn.m_cfm - row_delta_velocity(rn) * rn.m_jacDiagABInv;
        const btScalar ma = (st < 0 ? sc.forward : sc.backward) * btMax(N, btScalar(0));
        const btScalar mn = sc.transverse * btMax(N, btScalar(0));
        btScalar lt = 0, ln = 0;
        if (!(N > 0) || (ma == 0 && mn == 0)) {
            // No normal impulse or no friction: no friction impulse.
        } else if (st * st * mn * mn + sn * sn * ma * ma <= ma * ma * mn * mn) {
            lt = st;
            ln = sn;
        } else if (!(sc.kt > 0) || !(sc.kn > 0) || st == 0 || sn == 0) {
            // A row Bullet disabled (no effective mass), or sliding along t or n, where the law is
            // Coulomb's clamp: each row clamped on its own.
            lt = btMax(-ma, btMin(st, ma));
            ln = btMax(-mn, btMin(sn, mn));
        } else {
            const btScalar a0 = st * sc.kt, a1 = sn * sc.kn;
            const btScalar b0 = ma * sc.kt, b1 = mn * sc.kn;
            // Below the root, where one term alone is 1; s + b_i >= |a_i| > 0 from there on.
            const btScalar lo = btMax(btScalar(0), btMax(btFabs(a0) - b0, btFabs(a1) - b1));
            // Start from the previous iteration's root. Where that is above this root, the first step
            // (h convex and decreasing) lands below it, and the clamp at lo keeps it valid.
            btScalar s = btMax(lo, sc.s);
            for (int it = 0; it < 60; ++it) {
                // One division for both reciprocals: 1 / (s + b0) = (s + b1) / ((s + b0)(s + b1)).
                const btScalar p0 = s + b0, p1 = s + b1;
                const btScalar inv = 1 / (p0 * p1);
                const btScalar r0 = p1 * inv, r1 = p0 * inv;
                const btScalar q0 = a0 * r0, q1 = a1 * r1;
                const btScalar h = q0 * q0 + q1 * q1 - 1;
                const btScalar dh = q0 * q0 * r0 + q1 * q1 * r1;  // -h'(s) / 2
                if (!(dh > 0)) break;
                const btScalar step = h / (2 * dh);
                s = btMax(lo, s + step);
                // A relative step of 1e-10 leaves the impulse's error far below the solver's own.
                if (btFabs(step) <= btScalar(1e-10) * s) break;
            }
            sc.s = s;
            lt = ma * a0 / (s + b0);
            ln = mn * a1 / (s + b1);
        }
        const btScalar dt = lt - rt.m_appliedImpulse;
        const btScalar dn = ln - rn.m_appliedImpulse;
        rt.m_appliedImpulse = lt;
        rn.m_appliedImpulse = ln;
        apply_row_impulse(rt, dt);
        apply_row_impulse(rn, dn);
        const btScalar residual = dt * sc.kt + dn * sc.kn;
        return residual * residual;
    }

    btScalar solveSingleIteration(int iteration, btCollisionObject** bodies, int numBodies, btPersistentManifold** manifolds,
                                  int numManifolds, btTypedConstraint** constraints, int numConstraints,
                                  const btContactSolverInfo& info, btIDebugDraw* debug) override {
        btScalar residual = btMultiBodyConstraintSolver::solveSingleIteration(
            iteration, bodies, numBodies, manifolds, numManifolds, constraints, numConstraints, info, debug);
        // Bullet solves its friction rows only in the first m_numIterations iterations; so do these.
        if (iteration < info.m_numIterations)
            for (int k = 0; k < (int)m_skinContacts.size(); ++k) residual = btMax(residual, solve_skin_contact(k));
        return residual;
    }

    btScalar solveGroupCacheFriendlyFinish(btCollisionObject** bodies, int numBodies, const btContactSolverInfo& info) override {
        btMultiBodyConstraintArray& friction = m_multiBodyFrictionContactConstraints;
        for (int k = 0; k < (int)m_skinContacts.size(); ++k) {
            m_multiBodyNormalContactConstraints[m_skinContacts[k].normal].m_frictionIndex = friction.size();
            friction.push_back(m_skinRows[2 * k]);
            friction.push_back(m_skinRows[2 * k + 1]);
        }
        m_skinRows.resize(0);
        m_skinContacts.clear();
        return btMultiBodyConstraintSolver::solveGroupCacheFriendlyFinish(bodies, numBodies, info);
    }
};

}  // namespace

struct ss_world {
    // Declaration order is construction order; destruction runs in reverse, world first.
    std::unique_ptr<btDefaultCollisionConfiguration> config;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    std::unique_ptr<OrFilterCallback> filter;
    std::unique_ptr<btHashedOverlappingPairCache> pair_cache;
    std::unique_ptr<btDbvtBroadphase> broadphase;
    std::vector<Skin> skins;  // before the solver, which reads it
    std::unique_ptr<SkinSolver> solver;
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

namespace {

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

// POSITION_CONTROL on one joint (PSCP 7282-7345); max_velocity <= 0 leaves the rhs clamp as it is.
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
        w->solver.reset(new SkinSolver(&w->skins));
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
                               const double* forces, double kp, double kd) {
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
    }
    SS_GUARD_BEGIN
    // One command for all of them (PSCP 7282): each joint's motor in link order; the order of the joints
    // within the command does not matter, each motor is set once.
    for (int j = 0; j < count; ++j)
        set_position_motor(mb, joints[j], w->dt, targets[j], 0.0, forces[j], kp, kd, -1.0);
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

}  // extern "C"
