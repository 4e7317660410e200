/* scene_builder.h — the one way a ts_scene is made: a front end describes the scene call by
 * call, the builder checks what it is handed and builds the immutable scene.
 *
 * Design note: front ends (the JSON loader, scene_json.h; a pbrt-v3 importer) parse their
 * own text and check it in their own terms (JSON paths, file lines); the builder checks
 * every value it is handed — ranges, references to materials and files, the resource
 * limits — so every front end gets the same guarantees, and builds: mesh vertices to world
 * space, area lights for emitting shapes, the Embree accelerator, the light distribution,
 * the effects analysis (effects.h). Descriptors are in the renderer's own terms: object
 * space plus an object-to-world transform (the JSON v1 conveniences — a sphere's centre, a
 * disk's normal, a cylinder's p0/p1 — are the front end's to turn into a transform).
 *
 * Errors. Calls about the scene's settings (film, camera, sampler, integrator, job) write
 * sentences that name the setting ("film.crop: the window holds no pixel"). Calls that add
 * an element (material, shape, light) or read a file write a sentence that names no place;
 * the front end puts where the element came from in front with ts_error_prefix
 * ("shapes[3]: a transformed vertex is not a finite float"). Some values are checked where
 * the renderer's own components check them: the camera by ts_camera_init (at set_camera);
 * at finish, the finiteness of light colours, positions, directions and map transforms by
 * ts_lights_prepare ("lights[i]: …", i counting the lights in the order added, then one area
 * light per emitting sphere, disk or cylinder and per emitting mesh triangle, in shape
 * order), and shape sizes and transforms beyond the float range by the scene's bounds
 * ("shapes: the scene reaches beyond ±1e15 units …").
 *
 * Memory. The scene's arena (limits->max_memory) is made at create; names and mesh arrays
 * go into it as they are added, the material, shape and light lists grow in the builder's
 * own memory and are copied into the arena by finish. Files read through the builder
 * (Fourier tables, environment maps) belong to it, then to the scene. Whatever happens,
 * the caller calls ts_scene_builder_destroy once, which frees everything the scene did not
 * take: a failed call leaves the builder usable (the element was not added) and nothing is
 * half-built, so a front end may stop at its first error.
 *
 * Extension points: the elements are addressed by id (material id, shape id), descriptors
 * are tagged structs whose per-type parts are unions, so new kinds (textures, partial
 * quadrics, object instances, bump maps) come as new tags, fields and calls.
 *
 * A builder is used by one thread; its scene is immutable and thread-safe after finish. */
#ifndef TS_SCENE_BUILDER_H
#define TS_SCENE_BUILDER_H

#include <stdbool.h>
#include <stdint.h>

#include "camera/camera.h"
#include "core/cancel.h"
#include "core/error.h"
#include "core/transform.h"
#include "core/vecmath.h"
#include "film/filter.h"
#include "geometry/curve.h"
#include "geometry/shape.h"
#include "build/light_desc.h"
#include "lights/light.h"
#include "materials/material.h"
#include "sampling/sampler.h"
#include "mesh/mesh_read.h"
#include "scene/scene.h"
#include "textures/texture.h"
#include "textures/texture_cache.h"

/* Resource limits, checked before any large allocation. */
typedef struct ts_scene_limits {
    uint32_t max_width, max_height; /* film */
    uint64_t max_pixels;
    uint32_t max_spp;
    uint64_t max_triangles;                         /* all meshes together */
    uint32_t max_shapes, max_lights, max_materials; /* max_lights counts area lights too */
    uint64_t max_file_bytes;                        /* each referenced file */
    uint64_t max_memory;                            /* the scene arena */
    /* Stops the load (core/cancel.h): every builder call, the mesh and pbrt-v3 readers'
     * loops and the BVH build poll it; NULL (the default): never. Not owned. */
    ts_cancel *cancel;
} ts_scene_limits;

/* Generous defaults for the CLI (a server sets its own). */
void ts_scene_limits_default(ts_scene_limits *l);

typedef struct ts_scene_builder ts_scene_builder;

/* A new, empty builder (limits NULL: the defaults; copied). base_dir: the folder the
 * files a scene names are read from, with every path confined to it (scene_path.h), or
 * NULL to refuse every file reference. TS_ERR_NOMEM; *out NULL on failure. */
ts_status ts_scene_builder_create(const ts_scene_limits *limits, const char *base_dir, ts_scene_builder **out,
                                  ts_error *err);
/* Frees the builder and everything it holds that no finished scene took. NULL is fine. */
void ts_scene_builder_destroy(ts_scene_builder *b);

/* ---- settings: each may be set again (the last call wins); finish requires the film, the
 * camera, the sampler, the integrator and the digest. */

/* The scene's name (copied); without one the scene is "untitled". */
ts_status ts_scene_builder_set_name(ts_scene_builder *b, const char *name, ts_error *err);

/* The scene digest: 64 lower-case hex digits (copied), the front end's identity of its
 * document — the JSON front end's SHA-256 of the canonical document (scene_digest.h).
 * Farm shards refuse to merge across digests, so a scene has one. */
ts_status ts_scene_builder_set_digest(ts_scene_builder *b, const char *hex, ts_error *err);

typedef struct ts_film_desc {
    uint32_t width, height; /* pixels, within the limits */
    float crop[4];          /* x0, x1, y0, y1 in [0, 1], x0 < x1, y0 < y1 ({0, 1, 0, 1}: all);
                               the pixels [ceil(width·x0), ceil(width·x1)) × … (pbrt's rule) */
    ts_filter_type filter;
    float filter_radius; /* pixels, in (0, 16] */
    ts_filter_params filter_params; /* gaussian α, Mitchell B and C (filter.h); all zero: the defaults */
    float scale;                /* output factor of the pixel values, finite > 0 (0: 1) */
    float max_sample_luminance; /* a sample's luminance at most, > 0 (0 or INFINITY: no clamp) */
} ts_film_desc;
ts_status ts_scene_builder_set_film(ts_scene_builder *b, const ts_film_desc *film, ts_error *err);

/* Checked now (ts_camera_init's checks, then lens_radius finite ≥ 0 and focus_distance
 * finite > 0); the camera is set up at finish for the film's size. */
ts_status ts_scene_builder_set_camera(ts_scene_builder *b, const ts_camera_desc *camera, ts_error *err);

/* Sampler type and seed, and the samples per pixel, in [1, limits.max_spp]. */
ts_status ts_scene_builder_set_sampler(ts_scene_builder *b, const ts_sampler *sampler, uint32_t spp,
                                       ts_error *err);

/* The integrator a scene has when it names none, and the defaults of each field both front
 * ends start from: path, max_depth 5, rr_depth 3, lights selected by power, direct's
 * strategy "all" with MIS and one sample per light, ao_distance ∞. */
ts_integrator_desc ts_integrator_desc_default(void);

/* Ranges of the fields the type uses: path and volpath max_depth and rr_depth in [0, 65535]; direct
 * max_depth in [0, 1000] and samples_per_light in [1, 4096]; ao_distance > 0 (∞: any). */
ts_status ts_scene_builder_set_integrator(ts_scene_builder *b, const ts_integrator_desc *integrator,
                                          ts_error *err);

/* Optional (default: all zero). effects_off may hold TS_EFFECT_INDIRECT and
 * TS_EFFECT_DEPTH_OF_FIELD only; priority in [-1e6, 1e6]; spp 0 or in [1, max_spp];
 * time_limit_s and target_error finite ≥ 0; the name is copied. */
ts_status ts_scene_builder_set_job(ts_scene_builder *b, const ts_job_desc *job, ts_error *err);

/* ---- files a scene names (relative to base_dir, confined to it, each at most
 * limits.max_file_bytes), owned by the builder and then by the scene. Errors name the
 * file as written ("Fourier BSDF file 'x.bsdf': …", "environment map 'sky.exr': …",
 * "mesh file 'bunny.ply', line 3: …"); the caller prefixes where it was named. */

ts_status ts_scene_builder_load_fourier(ts_scene_builder *b, const char *rel_path,
                                        const struct ts_fourier_table **out, ts_error *err);
/* A lat-long environment map from an EXR file (envmap.h). */
ts_status ts_scene_builder_load_envmap(ts_scene_builder *b, const char *rel_path,
                                       const struct ts_envmap **out, ts_error *err);
/* An OBJ or PLY mesh (mesh_file.h) into *out, in the file's object space, owned by the
 * caller (ts_mesh_data_free) and meant for ts_scene_builder_add_shape; bounded by what is
 * left of limits.max_triangles ("the scene's triangles exceed the limit of N"). */
ts_status ts_scene_builder_load_mesh(ts_scene_builder *b, const char *rel_path, ts_mesh_data *out,
                                     ts_error *err);

/* pbrt-v3's `loopsubdiv` (mesh_subdiv.h): the limit surface of the control mesh (object
 * space; its positions and indices only) after `levels` Loop refinements, into *out
 * (object space, with normals; owned by the caller, ts_mesh_data_free) for
 * ts_scene_builder_add_shape, bounded by what is left of limits.max_triangles. */
ts_status ts_scene_builder_loop_subdivide(ts_scene_builder *b, const ts_mesh *control, uint32_t levels,
                                          ts_mesh_data *out, ts_error *err);

/* ---- textures (textures/texture.h; docs/design.md §4b, §4d). Textures live in the
 * scene's arena and their image maps in the scene's texture cache, both freed with the
 * scene. A front end makes them with ts_scene_builder_add_texture, or hands the arena,
 * the cache, the base folder and the file limit to another maker (the pbrt-v3 importer:
 * ts_texture_pbrt_build(tp, scene, ts_scene_builder_texture_arena(b), cache,
 * ts_scene_builder_base_dir(b), ts_scene_builder_limits(b)->max_file_bytes, err)), then
 * refers to them from material parameters (materials/material.h). */

/* The scene's arena, for textures (and only for what the scene keeps). */
ts_arena *ts_scene_builder_texture_arena(ts_scene_builder *b);
/* The scene's texture cache, made on the first call (its maps may take
 * limits.max_memory bytes together); TS_ERR_NOMEM. */
ts_status ts_scene_builder_texture_cache(ts_scene_builder *b, ts_texture_cache **out, ts_error *err);
/* The folder files are read from (NULL: none may be), and the limits in force. */
const char *ts_scene_builder_base_dir(const ts_scene_builder *b);
const ts_scene_limits *ts_scene_builder_limits(const ts_scene_builder *b);

/* Checks proto and copies it into the scene's arena (ts_texture_make: children and image
 * maps must be the scene's); *out the copy. Errors name the field ("tex1: …"). */
ts_status ts_scene_builder_add_texture(ts_scene_builder *b, const ts_texture *proto, const ts_texture **out,
                                       ts_error *err);
/* The MIP map of an image file (relative to base_dir, confined there, at most
 * limits.max_file_bytes) through the scene's cache: errors name the file as written
 * ("texture image 'x.png': …"). */
ts_status ts_scene_builder_load_texture_image(ts_scene_builder *b, const char *rel_path,
                                              const ts_texture_image_options *opt, const ts_mipmap **out,
                                              ts_error *err);

/* ---- elements */

/* Adds a material (copied) under name (copied; unique; NULL: an anonymous material no
 * name finds) and writes its id to *id (may be NULL). Checked: the type; constant colours
 * in [0, 1] (conductor eta and k finite ≥ 0); sigma in [0, 90] degrees; eta and roughness
 * finite (eta > 0, roughness ≥ 0); the distribution; a Fourier material's table loaded by
 * this builder; a textured parameter's texture (made for this scene, see above) of the
 * right kind: float parameters (sigma, eta, roughness) take float textures ("roughness:
 * expected a float texture, got an RGB one"), colour parameters either kind. The
 * material's `textured` flag is set here (the caller's is ignored). pbrt-v3's materials
 * (material.h lists their parameters and pbrt-v3's defaults, which the caller fills): a
 * mix names two materials added before by id (mix_id; mix[] is set by the builder) and
 * may have at most TS_BSDF_MAX_BXDFS lobes with them ("materials: the two materials mixed
 * have up to 9 lobes together, more than a BSDF's 8"); vroughness (has_vroughness) only
 * on conductor, dielectric, substrate and uber. At most limits.max_materials. */
ts_status ts_scene_builder_add_material(ts_scene_builder *b, const char *name, const ts_material *m,
                                        uint32_t *id, ts_error *err);
/* The id of the material added under name, or TS_NONE (also for name NULL). */
uint32_t ts_scene_builder_find_material(const ts_scene_builder *b, const char *name);

/* pbrt-v3's partial quadrics: its Sphere (zmin, zmax, phimax), Disk (phimax) and
 * Cylinder (zmin, zmax, phimax) parameters with pbrt-v3's semantics. `partial` false (the
 * zero value): the whole shape, the other fields unread. true: all three fields are read
 * (a front end passes pbrt-v3's defaults for the ones a file leaves out: zmin −radius,
 * zmax radius for a sphere, −1 and 1 for a cylinder, phimax 360):
 *   - phi_max: degrees, clamped to [0, 360] as pbrt-v3 does; the shape is the part with
 *     φ = atan2(y, x) in [0, phi_max] (object space);
 *   - sphere: z_min, z_max in either order, clamped to [−radius, radius] (pbrt-v3);
 *   - cylinder: the tube spans z from min(z_min, z_max) to max(z_min, z_max) (pbrt-v3),
 *     replacing the desc's 0 … height; the builder folds the offset into to_world;
 *   - disk: z_min and z_max unread (its height is the desc's own field).
 * A cut that leaves no area (phi_max 0, z_min = z_max after clamping) is refused; one that
 * keeps the whole shape is stored as the whole shape (same pixels, and the whole sphere's
 * cone sampling). */
typedef struct ts_shape_cut {
    bool partial;
    double z_min, z_max, phi_max;
} ts_shape_cut;

typedef struct ts_shape_desc {
    ts_shape_type type;
    uint32_t material; /* an id from ts_scene_builder_add_material, or TS_NONE: no surface (pbrt-v3's
                          Material "" / "none": the shape only bounds a medium; it cannot emit) */
    /* pbrt-v3's MediumInterface: with medium_interface set, the media (ids from
     * ts_scene_builder_add_medium, TS_NONE: vacuum) inside and outside (the front side's
     * medium); where they differ the shape is a transition (geometry/shape.h). */
    bool medium_interface;
    uint32_t medium_inside, medium_outside;
    ts_xform to_world; /* object → world (shape.h's object spaces) */
    ts_rgb emission;   /* radiance, each channel ≥ 0; not black: a diffuse area light */
    bool two_sided;    /* an emitter emits on both sides */
    uint32_t light_samples; /* an emitter: its samples per camera sample under direct's strategy all
                               (pbrt-v3's nsamples), in [1, 4096]; 0: the integrator's samples_per_light */
    /* pbrt-v3's ReverseOrientation: the front side (where a one-sided emitter emits, where
     * the normal points) becomes the other side. The builder applies exactly this flag; a
     * front end gives it as pbrt-v3's graphics state holds it (ReverseOrientation toggled
     * per attribute block) and must NOT fold in the handedness of to_world: the builder
     * already keeps every shape facing the way it faces in object space under a mirroring
     * transform, which is what pbrt-v3's XOR with TransformSwapsHandedness achieves. So
     * the world front side is: analytic shapes M^-T·n_obj (outwards, the disk's +z),
     * negated when set; meshes the object-space winding's side, reversed when set (the
     * builder swaps two indices of every triangle). */
    bool reverse_orientation;
    ts_shape_cut cut;  /* sphere, disk, cylinder only (zero for meshes) */
    /* Meshes only: pbrt-v3's alpha cut-outs (geometry/shape.h), float textures of this scene
     * (ts_scene_builder_add_texture), or NULL (opaque). A hit where alpha evaluates to
     * exactly 0 is no hit for any ray, one where shadow_alpha does none for shadow rays; a
     * front end turns a constant 0 into a constant texture and any other constant into
     * NULL (pbrt-v3's CreateTriangleMeshShape). An emitting mesh stays a light over all its
     * triangles (pbrt-v3 samples them whole). "alpha: expected a float texture, got an RGB
     * one"; "alpha: only meshes take alpha textures". */
    const ts_texture *alpha, *shadow_alpha;
    /* clang-format off */
    union {
        struct { double radius; } sphere;              /* > 0 */
        /* > 0; in [0, radius); pbrt-v3's height: the disk lies in the plane z = height */
        struct { double radius, inner_radius, height; } disk;
        struct { double radius, height; } cylinder;    /* > 0; > 0 unless cut.partial */
        ts_mesh mesh; /* object space, copied: n_vertices, n_triangles ≥ 1, finite positions,
                         indices < n_vertices, finite non-zero normals (or NULL), finite uvs
                         (or NULL) */
        /* pbrt-v3's curve (geometry/curve.h), as its CreateCurveShape reads it: n_points
         * finite control points p (object space, read during the call) of basis and degree
         * (2, 3) in a count pbrt-v3 takes that makes at least one segment; the width
         * linear from width0 to width1 (finite, > 0) over the segments; a ribbon's
         * n_normals = segments + 1 finite non-zero normals n (object space), other kinds
         * none. The builder makes the cubic Bézier segments, takes them to world space
         * (widths scaled by ∛|det| of to_world) and counts each segment against
         * limits.max_triangles. A curve cannot emit ("emission: pbrt-v3 cannot sample
         * curves …"), has no cut and no alpha. */
        struct {
            ts_curve_type type;
            ts_curve_basis basis;
            int degree;
            uint32_t n_points, n_normals;
            const float *p, *n;
            double width0, width1;
        } curve;
    };
    /* clang-format on */
} ts_shape_desc;

/* Adds a shape and writes its id to *id (may be NULL). A mesh is copied into the arena and
 * taken to world space (normals by the inverse transpose, their lengths kept: they weight
 * the interpolation as in pbrt-v3; a mirroring transform reverses the winding,
 * so each triangle keeps facing the way it faced in object space); "a transformed vertex is
 * not a finite float" when the transform takes a vertex beyond the float range. At most
 * limits.max_shapes shapes and limits.max_triangles triangles. */
ts_status ts_scene_builder_add_shape(ts_scene_builder *b, const ts_shape_desc *shape, uint32_t *id,
                                     ts_error *err);

/* ---- participating media (media/medium.h; docs/design.md §4): pbrt-v3's
 * MakeNamedMedium, checked here for both front ends. The scattering coefficients are
 * pbrt-v3's: σa and σs each the one given (has_*), else the preset's (pbrt-v3's
 * GetMediumScatteringProperties table; σs is its σ′s), else pbrt-v3's default (whole
 * milk, σa (.0011, .0024, .014), σs (2.55, 3.21, 3.77)), times scale. Refused: an unknown
 * preset ("preset: unknown medium preset \"x\""), σ not finite ≥ 0, scale not finite
 * ≥ 0, g outside (−1, 1), and for a grid nx, ny, nz not ≥ 1, a density count other than
 * nx·ny·nz ("density: 12 values, expected nx·ny·nz = 2·2·2 = 8"), a density not finite
 * ≥ 0, p0 not below p1 on every axis, σt = σa + σs not the same in every channel (the
 * trackers' majorant is grey, as pbrt-v3's) and a to_world that is not finite and
 * invertible. At most 65536 media. */
typedef struct ts_medium_desc {
    ts_medium_type type;
    const char *preset; /* NULL: none */
    bool has_sigma_a, has_sigma_s;
    ts_rgb sigma_a, sigma_s; /* per unit length */
    double scale;            /* the front end passes 1 for none */
    double g;
    /* grid only */
    uint32_t nx, ny, nz;
    const float *density; /* n_density values (copied), x fastest: [(z·ny + y)·nx + x] */
    uint64_t n_density;
    ts_dvec3 p0, p1;      /* the grid's box in the medium's space */
    ts_xform to_world;    /* medium space → world */
} ts_medium_desc;

/* Adds a medium under name (copied, unique; NULL: anonymous) and writes its id to *id. */
ts_status ts_scene_builder_add_medium(ts_scene_builder *b, const char *name, const ts_medium_desc *m,
                                      uint32_t *id, ts_error *err);
/* The id of the medium added under name, or TS_NONE. */
uint32_t ts_scene_builder_find_medium(const ts_scene_builder *b, const char *name);
/* The medium camera rays start in (pbrt-v3's camera medium): an id, or TS_NONE (vacuum,
 * the default). */
ts_status ts_scene_builder_set_camera_medium(ts_scene_builder *b, uint32_t medium, ts_error *err);

/* ---- object instancing (pbrt-v3's ObjectBegin/End, ObjectInstance; geometry/accel.h)
 *
 * begin_object opens the definition of a named object (names unique; *id may be NULL):
 * until end_object every ts_scene_builder_add_shape adds to it, the shape's to_world
 * placing it in the object's own space (pbrt-v3: the CTM at the Shape inside
 * ObjectBegin/End); add_instance's to_world is pbrt-v3's CTM at ObjectInstance, so a point
 * of the shape lands at to_world(shape to_world(p)), as in pbrt-v3. add_instance places
 * the object in the world by to_world (finite and invertible); any number of instances
 * share the object's geometry. Refused: a definition or an instance inside a definition
 * (TS_ERR_UNSUPPORTED: no nesting, as in pbrt-v3), an emitting shape inside a definition
 * (TS_ERR_UNSUPPORTED; pbrt-v3 warns "area lights not supported with object instancing"
 * and keeps the shape without its emission — the pbrt-v3 front end does that, with the
 * warning), finish with a definition open. Instances count against limits.max_shapes with
 * the shapes; an object's triangles count once. */
ts_status ts_scene_builder_begin_object(ts_scene_builder *b, const char *name, uint32_t *id, ts_error *err);
ts_status ts_scene_builder_end_object(ts_scene_builder *b, ts_error *err);
/* The id of the object named name, or TS_NONE. */
uint32_t ts_scene_builder_find_object(const ts_scene_builder *b, const char *name);
ts_status ts_scene_builder_add_instance(ts_scene_builder *b, uint32_t object, const ts_xform *to_world,
                                        ts_error *err);

/* ---- motion blur (pbrt-v3's animated transforms; core/animated_transform.h, accel.h)
 *
 * add_moving_instance: an instance whose object-to-world moves from start (at t0) to end
 * (at t1), interpolated as pbrt's AnimatedTransform. add_moving_shape: pbrt-v3's shape
 * under an animated CTM — the shape in an object of its own, placed there by d->to_world
 * (the shape's own placement: a disk's height, a cylinder's z range; the identity for a
 * mesh), and a moving instance of it from start to end; *id is the shape's. Both: equal
 * keyframes are no motion (the static call, bit for bit: add_shape with to_world
 * start ∘ d->to_world); refused
 * ("motion.times: the end time 0 must be after the start time 1") when the keyframes
 * differ and t1 ≤ t0, a keyframe that is not finite, invertible and affine; a moving
 * shape that emits ("emission: a moving shape cannot emit …", TS_ERR_UNSUPPORTED; the
 * pbrt-v3 front end drops the area light with pbrt-v3's warning) or inside an object
 * definition (TS_ERR_UNSUPPORTED: instances do not nest). The instance is counted as
 * add_instance's; a moving shape as a shape, an object and an instance. */
ts_status ts_scene_builder_add_moving_instance(ts_scene_builder *b, uint32_t object, const ts_xform *start,
                                               double t0, const ts_xform *end, double t1, ts_error *err);
ts_status ts_scene_builder_add_moving_shape(ts_scene_builder *b, const ts_shape_desc *d, const ts_xform *start,
                                            double t0, const ts_xform *end, double t1, uint32_t *id, ts_error *err);

/* Adds a light (with the area lights of the shapes added so far, at most
 * limits.max_lights). */
ts_status ts_scene_builder_add_light(ts_scene_builder *b, const ts_light_desc *light, ts_error *err);

/* What has been added so far. */
typedef struct ts_scene_counts {
    uint32_t materials, shapes, lights; /* lights: added with add_light */
    uint64_t triangles;                 /* of every mesh */
    uint64_t area_lights;               /* emitting analytic shapes + emitting triangles */
    uint32_t objects, instances;
} ts_scene_counts;
void ts_scene_builder_counts(const ts_scene_builder *b, ts_scene_counts *out);

/* ---- the scene */

/* Builds the scene: the area lights, the camera for the film, the accelerator (and its
 * bounds, which must stay within ±1e15 units, as must the camera), the lights
 * (ts_lights_prepare), the light distribution (uniform for a path integrator that asks for
 * it, else by power), the effects analysis less the job's switches. On success *out is the
 * scene (the caller destroys it with ts_scene_destroy); on failure *out is NULL. Either
 * way the builder accepts no more calls but ts_scene_builder_destroy. */
ts_status ts_scene_builder_finish(ts_scene_builder *b, ts_scene **out, ts_error *err);

#endif
