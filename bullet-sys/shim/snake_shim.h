/*
 * snake_shim.h: a thin C interface over Bullet's btMultiBody API that builds and steps a world the way
 * pybullet 3.2.7 (p.connect(p.DIRECT)) does, so that a snake simulated through it moves bit for bit as
 * pybullet's does. Every setting and call order follows docs/parity.md and the bullet3 sources it
 * cites (PhysicsServerCommandProcessor.cpp, URDF2Bullet.cpp).
 *
 * Conventions:
 * - Every function that can fail returns an int status: SS_OK (0) or a negative SS_ERR_* code; the text
 *   of the most recent failure on the calling thread is available from ss_last_error().
 * - No C++ exception crosses this boundary.
 * - Bodies are numbered in creation order from 0 within one world; joints and links are numbered from 0
 *   (link -1 is the base), as in pybullet.
 * - Quaternions are (x, y, z, w).
 */
#ifndef SNAKE_SHIM_H
#define SNAKE_SHIM_H

#ifdef __cplusplus
extern "C" {
#endif

#define SS_OK 0
#define SS_ERR_NULL (-1)      /* a required pointer was NULL */
#define SS_ERR_ARGUMENT (-2)  /* an argument is out of range or not finite */
#define SS_ERR_BODY (-3)      /* no such body in this world */
#define SS_ERR_LINK (-4)      /* no such link or joint on that body */
#define SS_ERR_EXCEPTION (-5) /* Bullet or the C++ runtime threw (e.g. out of memory) */

#define SS_POSITION_CONTROL 0 /* pybullet POSITION_CONTROL (CONTROL_MODE_POSITION_VELOCITY_PD) */
#define SS_VELOCITY_CONTROL 1 /* pybullet VELOCITY_CONTROL */
#define SS_TORQUE_CONTROL 2   /* pybullet TORQUE_CONTROL */

typedef struct ss_world ss_world;

/* A multibody of boxes that all share one box collision shape, joined by revolute joints, as
 * pybullet's createMultiBody builds it from one GEOM_BOX shape. Inertial frames are the link frames. */
typedef struct ss_chain_desc {
    double half_extents[3];
    double base_mass;          /* 0 makes a fixed base */
    double base_position[3];   /* base COM position in world */
    double base_orientation[4];
    int num_links;
    const double* link_masses;       /* num_links */
    const double* link_positions;    /* 3 * num_links: joint frame in the parent's link frame */
    const double* link_orientations; /* 4 * num_links */
    const int* link_parents;         /* num_links; pybullet convention: 0 = base, k = link k - 1 */
    const double* link_axes;         /* 3 * num_links: revolute axis in the link frame */
} ss_chain_desc;

/* URDF robots (pybullet's loadURDF with default flags, or URDF_USE_INERTIA_FROM_FILE). The caller parses
 * the file; the shim builds the multibody from the parsed numbers as BulletURDFImporter and
 * ConvertURDF2Bullet do, including the rpy -> quaternion step, the inertia and every Bullet call's order. */
#define SS_SHAPE_BOX 1      /* size = full extents x, y, z */
#define SS_SHAPE_SPHERE 2   /* size[0] = radius */
#define SS_SHAPE_CYLINDER 3 /* size[0] = radius, size[1] = length (along z); a 64-vertex convex hull */
#define SS_SHAPE_CAPSULE 4  /* size[0] = radius, size[1] = length of the cylinder part (along z) */

#define SS_JOINT_REVOLUTE 1   /* values as pybullet's UrdfJointTypes */
#define SS_JOINT_PRISMATIC 2
#define SS_JOINT_CONTINUOUS 3
#define SS_JOINT_FIXED 6

/* Flags of ss_urdf_contact.flags: pybullet's URDF_LinkContactFlags (lateral friction is always set). */
#define SS_CONTACT_INERTIA_SCALING 2
#define SS_CONTACT_STIFFNESS_DAMPING 16
#define SS_CONTACT_ROLLING_FRICTION 32
#define SS_CONTACT_SPINNING_FRICTION 64
#define SS_CONTACT_RESTITUTION 128
#define SS_CONTACT_FRICTION_ANCHOR 256

/* An <origin xyz rpy>: has_rpy 0 leaves the rotation at the identity, as a missing rpy attribute does. */
typedef struct ss_urdf_origin {
    double xyz[3];
    double rpy[3];
    int has_rpy;
} ss_urdf_origin;

typedef struct ss_urdf_shape {
    int type; /* SS_SHAPE_* */
    double size[3];
    ss_urdf_origin origin;
} ss_urdf_shape;

/* pybullet's <contact> extension of a link, with the parser's defaults for what is absent. */
typedef struct ss_urdf_contact {
    int flags;
    double lateral_friction; /* 0.5 when absent */
    double rolling_friction;
    double spinning_friction;
    double restitution;
    double inertia_scaling;
    double stiffness; /* 1e4 when only damping is given */
    double damping;   /* 1 when only stiffness is given */
} ss_urdf_contact;

typedef struct ss_urdf_link {
    int parent; /* index in ss_urdf_desc.links of the parent; -1 for the root (links[0]) */
    /* <inertial>: a link without one has mass 1 and inertia diagonal (1, 1, 1), identity frame. */
    double mass;
    ss_urdf_origin inertial_origin;
    double inertia[6]; /* ixx, ixy, ixz, iyy, iyz, izz */
    int num_shapes;
    const ss_urdf_shape* shapes; /* the link's <collision> elements in file order */
    int has_collision_group, collision_group, has_collision_mask, collision_mask;
    ss_urdf_contact contact;
    /* The joint from the parent (ignored for the root). */
    int joint_type; /* SS_JOINT_* */
    ss_urdf_origin joint_origin;
    double axis[3];
    double lower, upper, effort, velocity, damping, friction; /* the parser's values and defaults */
} ss_urdf_link;

typedef struct ss_urdf_desc {
    int num_links;               /* links including the root; the body has num_links - 1 joints */
    const ss_urdf_link* links;   /* in pybullet's order: depth first from the root, children in joint order */
    double base_position[3];     /* loadURDF basePosition: the root link frame, not its centre of mass */
    double base_orientation[4];  /* loadURDF baseOrientation */
    int inertia_from_file;       /* URDF_USE_INERTIA_FROM_FILE */
} ss_urdf_desc;

/* pybullet changeDynamics: a field is applied only when "set" (>= 0 for scalars, flag != 0 otherwise),
 * exactly as pybullet sends only the arguments given. */
typedef struct ss_dynamics {
    double lateral_friction;
    double spinning_friction;
    double rolling_friction;
    double restitution;
    double linear_damping;  /* whole body */
    double angular_damping; /* whole body */
    double joint_damping;   /* links only */
    int has_anisotropic_friction;
    double anisotropic_friction[3];
    int friction_anchor; /* -1 leave as is, 0 clear, 1 set */
} ss_dynamics;

typedef struct ss_base_state {
    double position[3];    /* base COM, world frame (getBasePositionAndOrientation) */
    double orientation[4]; /* through pybullet's quaternion -> matrix -> quaternion round trip */
    double linear_velocity[3];
    double angular_velocity[3];
} ss_base_state;

typedef struct ss_contact {
    int link;                  /* link of the queried body, -1 for its base */
    int other_body;            /* body index of the other object, -1 if it is not a multibody */
    int other_link;
    double position_on_body[3];
    double position_on_other[3];
    double normal_on_other[3]; /* contact normal, pointing from the other object towards the body */
    double distance;
    double normal_force;       /* applied impulse / dt of the last step */
} ss_contact;

/* Text of the last failure on this thread ("" if none). Valid until the next failing call. */
const char* ss_last_error(void);

/* A new world as p.connect(p.DIRECT) makes it: dt 1/240, gravity 0, pybullet's solver settings. */
ss_world* ss_world_new(void);
void ss_world_free(ss_world* world);

int ss_world_set_gravity(ss_world* world, double gx, double gy, double gz);
int ss_world_set_time_step(ss_world* world, double dt);
int ss_world_num_bodies(const ss_world* world, int* count);

/* createMultiBody(0, createCollisionShape(GEOM_PLANE)): a static plane z = 0. */
int ss_world_add_plane(ss_world* world, int* body_out);

/* A static body of a world file: createMultiBody(0, createCollisionShape(type, ...), -1, position,
 * orientation). Types have pybullet's GEOM_* values. */
#define SS_GEOM_SPHERE 2      /* size[0] = radius */
#define SS_GEOM_BOX 3         /* size = half extents (createCollisionShape's halfExtents) */
#define SS_GEOM_CYLINDER 4    /* size[0] = radius, size[1] = height (along z): btCylinderShapeZ */
#define SS_GEOM_PLANE 6       /* normal (0, 0, 1), constant 0 */
#define SS_GEOM_HEIGHTFIELD 9 /* size = meshScale; heights, rows, columns below */

typedef struct ss_static_desc {
    int type; /* SS_GEOM_* */
    double size[3];
    double position[3];
    double orientation[4];
    /* GEOM_HEIGHTFIELD with heightfieldData: numHeightfieldRows (values per grid line, along x) and
     * numHeightfieldColumns (lines, along y); heights[y * rows + x], float32 as pybullet's client
     * sends them. */
    int rows;
    int columns;
    const float* heights;
} ss_static_desc;

/* Adds a static body (see ss_static_desc); the ground and a world file's obstacles. */
int ss_world_add_static(ss_world* world, const ss_static_desc* desc, int* body_out);
/* createMultiBody(...) with one box shape for every cube, then pybullet's default joint motors. */
int ss_world_add_box_chain(ss_world* world, const ss_chain_desc* desc, int* body_out);

/* loadURDF(...) of a parsed robot (see ss_urdf_desc), then pybullet's default joint motors on every
 * revolute and prismatic joint. Joint j of the body is links[j + 1]. */
int ss_world_add_urdf(ss_world* world, const ss_urdf_desc* desc, int* body_out);

int ss_body_num_joints(const ss_world* world, int body, int* count);
/* changeDynamics(body, link, ...); link -1 is the base. */
int ss_change_dynamics(ss_world* world, int body, int link, const ss_dynamics* dynamics);

/* changeDynamics(body, link, mass=mass): the part's mass, and its local inertia recomputed from its
 * collision shape as pybullet does (PSCP processChangeDynamicsInfoCommand: setBaseMass / m_mass, then
 * shape->calculateLocalInertia(mass) into setBaseInertia / m_inertiaLocal; an inertia read from a URDF
 * file is replaced, as in pybullet). mass must be finite and > 0, and the part dynamic (mass > 0; a fixed
 * base or a massless link is refused: pybullet would switch a base between fixed and dynamic). */
int ss_set_mass(ss_world* world, int body, int link, double mass);

/* getDynamicsInfo(body, link): mass, lateral friction and the local inertia diagonal (3 values). */
int ss_get_dynamics_info(const ss_world* world, int body, int link, double* mass, double* lateral_friction,
                         double* inertia);

/* Multiplies the skin friction coefficients of link `link` (-1: the base) by `factor` (finite, >= 0);
 * *had_skin is 1 if the link has skin friction, 0 if not (nothing changes then). */
int ss_scale_skin_friction(ss_world* world, int body, int link, double factor, int* had_skin);

/* Skin friction (Hu, Nirody, Scott and Shelley 2009) on link `link` (-1: the base) of `body`: a contact
 * of that link sliding with unit velocity u (relative to the other object, in the contact plane) gets the
 * friction force -N (mu_t (u.n) n + mu_a (u.t) t), t the skin axis projected into the contact plane, n the
 * in-plane normal to t, mu_a = forward when u.t > 0 (sliding head first), backward otherwise; a sticking
 * contact gets any force inside the set that law allows (a half ellipse of semi-axes mu_f N and mu_t N
 * behind, one of mu_b N and mu_t N ahead). Where the axis leaves the contact plane, forward and backward
 * blend into transverse in proportion to the sine of its angle with the normal (all transverse when the
 * axis is normal to the plane, where the law leaves t undefined). Each coefficient is multiplied by the other object's lateral
 * friction (clamped to 10, as Bullet combines lateral friction). The link's own lateral and anisotropic
 * friction no longer act on its contacts (rolling and spinning friction do). `axis` is the head direction
 * in the link frame (for a URDF link, its <link> frame, not its inertial frame); it must be non-zero.
 * Coefficients must be finite and >= 0. Worlds without skin friction step exactly as before. */
int ss_set_skin_friction(ss_world* world, int body, int link, double forward, double backward, double transverse,
                         const double* axis);

/* setJointMotorControl2(body, joint, mode, targetPosition, targetVelocity, force, positionGain,
 * velocityGain, maxVelocity); max_velocity <= 0 means "not given". For SS_TORQUE_CONTROL, force is the
 * torque added until the end of the next step. */
int ss_set_joint_motor(ss_world* world, int body, int joint, int mode, double target_position,
                       double target_velocity, double force, double kp, double kd, double max_velocity);
/* POSITION_CONTROL with target velocity 0 on joints 0..count-1: the same effect as count calls of
 * ss_set_joint_motor, in one crossing. */
int ss_set_position_targets(ss_world* world, int body, int count, const double* targets, double force,
                            double kp, double kd);

/* setJointMotorControlArray(body, joints, POSITION_CONTROL, targetPositions, forces, positionGains=kp,
 * velocityGains=kd) on the given joints (each must have a motor: revolute or prismatic). max_velocities
 * is NULL (none given: exactly setJointMotorControlArray) or holds count values, each joint's
 * setJointMotorControl2 maxVelocity (rad/s, m/s for a prismatic joint): a value > 0 becomes the motor's
 * rhs clamp, 0 leaves that joint's clamp as it is (pybullet's "not given"); a negative or non-finite
 * value is SS_ERR_ARGUMENT. */
int ss_set_position_targets_at(ss_world* world, int body, int count, const int* joints, const double* targets,
                               const double* forces, double kp, double kd, const double* max_velocities);

/* p.stepSimulation(): joint damping torques, then one internal step of dt. */
int ss_world_step(ss_world* world);

int ss_get_base_state(const ss_world* world, int body, ss_base_state* out);
/* getJointStates for joints 0..count-1; any output pointer may be NULL. applied_torque is the motor's
 * applied impulse / dt, as pybullet reports it. */
int ss_get_joint_states(const ss_world* world, int body, int count, double* positions,
                        double* velocities, double* applied_torques);
/* getJointStates(body, joints) for the given joints; output pointers as for ss_get_joint_states. */
int ss_get_joint_states_at(const ss_world* world, int body, int count, const int* joints, double* positions,
                           double* velocities, double* applied_torques);
/* World pose of each link's COM frame, 7 values (x, y, z, qx, qy, qz, qw) per link 0..count-1. */
int ss_get_link_poses(const ss_world* world, int body, int count, double* poses);
/* Poses of the collision shapes of link `link` (-1: the base) in its centre-of-mass frame, 7 values
 * each (x, y, z, qx, qy, qz, qw), in the order of the URDF's <collision> elements; *count_out is their
 * number (one identity pose when the importer used the single shape directly). */
int ss_get_shape_poses(const ss_world* world, int body, int link, double* poses, int capacity, int* count_out);
/* World-frame velocities of each link's centre of mass, 6 values (vx, vy, vz, wx, wy, wz) per link
 * 0..count-1, as getLinkState(computeLinkVelocity=1) computes them (compTreeLinkVelocities). */
int ss_get_link_velocities(const ss_world* world, int body, int count, double* velocities);
/* applyExternalForce(body, link, force, position, WORLD_FRAME): `force` (N) at the world point
 * `position`, on link `link` (-1: the base); it acts during the next ss_world_step only. */
int ss_apply_external_force(ss_world* world, int body, int link, const double force[3], const double position[3]);
/* applyExternalTorque(body, link, torque, WORLD_FRAME), for the next step only. */
int ss_apply_external_torque(ss_world* world, int body, int link, const double torque[3]);
/* resetBasePositionAndOrientation and resetBaseVelocity together: the base's centre of mass pose and its
 * world-frame velocities; the links follow (forward kinematics, collider transforms). */
int ss_reset_base_state(ss_world* world, int body, const ss_base_state* state);
/* resetJointState(body, j, positions[j], velocities[j]) for joints 0..count-1. */
int ss_reset_joint_states(ss_world* world, int body, int count, const double* positions, const double* velocities);
/* Contact points of the last step that involve `body`, up to `capacity`; *count_out is the total. */
int ss_get_contacts(const ss_world* world, int body, ss_contact* out, int capacity, int* count_out);

#ifdef __cplusplus
}
#endif

#endif /* SNAKE_SHIM_H */
