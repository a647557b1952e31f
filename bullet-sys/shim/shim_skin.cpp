// shim_skin.cpp: the skin-friction solver; see shim_internal.h for the shim's files.

#include "shim_internal.h"

#include <vector>

namespace snake_shim {
namespace {

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

std::unique_ptr<btMultiBodyConstraintSolver> new_skin_solver(const std::vector<Skin>* skins) {
    return std::unique_ptr<btMultiBodyConstraintSolver>(new SkinSolver(skins));
}

}  // namespace snake_shim
