/* camera.h — perspective (with thin lens) and orthographic cameras of scene format v1.
 *
 * Design note: the camera is defined by from/to/up as docs/design.md §4: forward = to − from,
 * right = normalize(forward × up), and the true up = right × forward. Raster (0,0) is the
 * top-left corner of the top-left pixel and y grows downwards. `fov` is the full angle
 * along the shorter image axis (as pbrt); an orthographic camera's `height` is the screen
 * window height in scene units. Thin lens: a lens sample on the disk of lens_radius is
 * focused at focus_distance along forward. Two options serve pbrt-v3 scenes (docs/pbrt-v3.md):
 * `mirror` makes right = up × forward instead (pbrt-v3's camera space is left-handed: its
 * image x runs along camera +x, which a right-handed from/to/up frame cannot express), and
 * an explicit screen window [x0, x1] × [y0, y1] replaces the one centred on the view
 * direction: for a perspective camera in units of tan(fov/2) (pbrt-v3's `screenwindow`),
 * for an orthographic one in scene units (then `height` is not used). Immutable after
 * init; thread-safe. */
#ifndef TS_CAMERA_H
#define TS_CAMERA_H

#include "core/animated_transform.h"
#include "core/error.h"
#include "core/vecmath.h"
#include "geometry/interaction.h"

typedef enum ts_camera_type { TS_CAMERA_PERSPECTIVE, TS_CAMERA_ORTHOGRAPHIC } ts_camera_type;

typedef struct ts_camera {
    ts_camera_type type;
    ts_vec3 origin, forward, right, up; /* unit, orthonormal */
    float fov_deg;                      /* perspective */
    float ortho_height;                 /* orthographic */
    float lens_radius, focus_distance;
    int width, height;
    float half_w, half_h; /* screen window half extents: at distance 1 (perspective) or in scene units */
    float center_x, center_y; /* the window's centre in the same units (0 unless a window was given) */
    /* Motion blur (pbrt-v3's animated CameraToWorld and shutter): a ray's time is
     * lerp(u, shutter_open, shutter_close) (ts_camera_time); the frame above is the
     * camera at motion.start_time, and a ray made by it is moved to its time by
     * M(time)·M(start)⁻¹, M the interpolated camera-to-world keyframes
     * (core/animated_transform.h) — the identity, untouched, at or before the start. */
    float shutter_open, shutter_close;
    bool moving;          /* motion.animated */
    ts_anim_xform motion; /* camera → world keyframes (only read when moving) */
} ts_camera;

typedef struct ts_camera_desc {
    ts_camera_type type;
    ts_vec3 from, to, up;
    float fov_deg, ortho_height, lens_radius, focus_distance;
    bool mirror;       /* right = up × forward (pbrt-v3's left-handed camera space) */
    bool has_window;   /* screen_window is given */
    float screen_window[4]; /* x0, x1, y0, y1 (x0 < x1, y0 < y1): see the design note */
    float shutter_open, shutter_close; /* finite, open ≤ close (pbrt-v3's defaults 0, 1) */
    /* moving: the camera-to-world keyframes at motion_t0 < motion_t1 (equal keyframes: no
     * motion); the frame from/to/up above is the one at motion_t0. */
    bool moving;
    ts_xform motion_start, motion_end;
    double motion_t0, motion_t1;
} ts_camera_desc;

/* Fails (TS_ERR_INVALID, sentence) if from == to, up is parallel to the view direction,
 * or a parameter is out of range. */
ts_status ts_camera_init(ts_camera *cam, const ts_camera_desc *desc, int width, int height, ts_error *err);

/* The primary ray through raster point p_raster (pixels), with lens sample u_lens in [0,1)²,
 * at the start of the camera's motion (time 0 in the ray). */
ts_ray ts_camera_ray(const ts_camera *cam, ts_vec2 p_raster, ts_vec2 u_lens);
/* The time of shutter sample u in [0, 1). */
float ts_camera_time(const ts_camera *cam, float u);
/* Sets the ray's time and moves it with the camera to that time (see ts_camera). */
void ts_camera_move_ray(const ts_camera *cam, ts_ray *ray, float time);
/* The same motion for n origins and directions (a ray's differentials). */
void ts_camera_move_points(const ts_camera *cam, float time, ts_vec3 *o, ts_vec3 *d, int n);

#endif
