/* camera.c — primary rays; see camera.h. */
#include "camera/camera.h"

#include <math.h>

#include "sampling/sampling.h"

/* The shutter and the keyframes (camera.h). */
static ts_status camera_motion(ts_camera *cam, const ts_camera_desc *d, ts_error *err)
{
    cam->shutter_open = d->shutter_open;
    cam->shutter_close = d->shutter_close;
    if (!isfinite(d->shutter_open) || !isfinite(d->shutter_close) || d->shutter_close < d->shutter_open)
        return ts_error_set(err, TS_ERR_INVALID,
                            "camera.shutter: expected [open, close] with open ≤ close, got [%g, %g]",
                            d->shutter_open, d->shutter_close);
    if (!d->moving) return TS_OK;
    if (!ts_anim_xform_init(&cam->motion, &d->motion_start, d->motion_t0, &d->motion_end, d->motion_t1))
        return ts_error_set(err, TS_ERR_INVALID,
                            "camera.motion: expected times [t0, t1] with t0 < t1 and invertible affine "
                            "start and end transforms");
    cam->moving = cam->motion.animated;
    return TS_OK;
}

ts_status ts_camera_init(ts_camera *cam, const ts_camera_desc *d, int width, int height, ts_error *err)
{
    ts_vec3 fwd = ts_vec3_sub(d->to, d->from);
    if (ts_vec3_length(fwd) == 0) return ts_error_set(err, TS_ERR_INVALID, "camera: 'from' and 'to' are the same point");
    fwd = ts_vec3_normalize(fwd);
    ts_vec3 right = ts_vec3_cross(fwd, d->up);
    if (!(ts_vec3_length(right) > 1e-6f * ts_vec3_length(d->up)))
        return ts_error_set(err, TS_ERR_INVALID, "camera.up: must not be parallel to the view direction");
    right = ts_vec3_normalize(right);
    ts_vec3 up = ts_vec3_normalize(ts_vec3_cross(right, fwd));
    if (d->mirror) right = ts_vec3_scale(right, -1);
    if (width <= 0 || height <= 0) return ts_error_set(err, TS_ERR_INVALID, "film: width and height must be positive");

    *cam = (ts_camera){0};
    cam->type = d->type;
    cam->origin = d->from;
    cam->forward = fwd;
    cam->right = right;
    cam->up = up;
    cam->fov_deg = d->fov_deg;
    cam->ortho_height = d->ortho_height;
    cam->lens_radius = d->lens_radius;
    cam->focus_distance = d->focus_distance;
    cam->width = width;
    cam->height = height;
    ts_status st = camera_motion(cam, d, err);
    if (st) return st;

    float aspect = (float)width / (float)height;
    float half_short;
    if (d->has_window) {
        const float *w = d->screen_window;
        if (!(isfinite(w[0]) && isfinite(w[1]) && isfinite(w[2]) && isfinite(w[3]) && w[0] < w[1] && w[2] < w[3]))
            return ts_error_set(err, TS_ERR_INVALID,
                                "camera.screen_window: expected [x0, x1, y0, y1] with x0 < x1 and y0 < y1");
        float unit = 1;
        if (d->type == TS_CAMERA_PERSPECTIVE) {
            if (!(d->fov_deg > 0 && d->fov_deg < 180))
                return ts_error_set(err, TS_ERR_INVALID, "camera.fov: expected an angle in (0, 180), got %g",
                                    d->fov_deg);
            unit = tanf(ts_radians(d->fov_deg) * 0.5f);
        }
        cam->half_w = 0.5f * (w[1] - w[0]) * unit;
        cam->half_h = 0.5f * (w[3] - w[2]) * unit;
        cam->center_x = 0.5f * (w[1] + w[0]) * unit;
        cam->center_y = 0.5f * (w[3] + w[2]) * unit;
        return TS_OK;
    }
    if (d->type == TS_CAMERA_PERSPECTIVE) {
        if (!(d->fov_deg > 0 && d->fov_deg < 180))
            return ts_error_set(err, TS_ERR_INVALID, "camera.fov: expected an angle in (0, 180), got %g", d->fov_deg);
        half_short = tanf(ts_radians(d->fov_deg) * 0.5f);
        if (width >= height) {
            cam->half_h = half_short;
            cam->half_w = half_short * aspect;
        } else {
            cam->half_w = half_short;
            cam->half_h = half_short / aspect;
        }
    } else {
        if (!(d->ortho_height > 0))
            return ts_error_set(err, TS_ERR_INVALID, "camera.height: expected a positive number, got %g", d->ortho_height);
        cam->half_h = d->ortho_height * 0.5f;
        cam->half_w = cam->half_h * aspect;
    }
    return TS_OK;
}

ts_ray ts_camera_ray(const ts_camera *cam, ts_vec2 p_raster, ts_vec2 u_lens)
{
    float sx = (2.0f * p_raster.x / (float)cam->width - 1.0f) * cam->half_w + cam->center_x;
    float sy = (1.0f - 2.0f * p_raster.y / (float)cam->height) * cam->half_h + cam->center_y;
    ts_vec3 o, d;
    if (cam->type == TS_CAMERA_PERSPECTIVE) {
        o = cam->origin;
        d = ts_vec3_add(cam->forward, ts_vec3_add(ts_vec3_scale(cam->right, sx), ts_vec3_scale(cam->up, sy)));
        d = ts_vec3_normalize(d);
    } else {
        o = ts_vec3_add(cam->origin, ts_vec3_add(ts_vec3_scale(cam->right, sx), ts_vec3_scale(cam->up, sy)));
        d = cam->forward;
    }
    if (cam->lens_radius > 0) {
        /* Focus plane at focus_distance along forward; the lens point moves the origin. */
        ts_vec2 lens = ts_sample_concentric_disk(u_lens);
        float ft = cam->focus_distance / ts_vec3_dot(d, cam->forward);
        ts_vec3 p_focus = ts_vec3_add(o, ts_vec3_scale(d, ft));
        o = ts_vec3_add(o, ts_vec3_add(ts_vec3_scale(cam->right, lens.x * cam->lens_radius),
                                       ts_vec3_scale(cam->up, lens.y * cam->lens_radius)));
        d = ts_vec3_normalize(ts_vec3_sub(p_focus, o));
    }
    return ts_ray_make(o, d, INFINITY);
}

void ts_camera_move_ray(const ts_camera *cam, ts_ray *ray, float time)
{
    ray->time = time;
    ts_camera_move_points(cam, time, &ray->o, &ray->d, 1);
}

void ts_camera_move_points(const ts_camera *cam, float time, ts_vec3 *o, ts_vec3 *d, int n)
{
    if (!cam->moving || time <= cam->motion.start_time) return;
    /* world ← camera at time ← camera at the start, in double, rounded once. */
    ts_mat4 m = ts_anim_xform_matrix(&cam->motion, time);
    ts_mat4 delta = ts_mat4_mul(&m, &cam->motion.start.m_inv);
    ts_xform x = {delta, delta}; /* only the forward matrix is read */
    for (int i = 0; i < n; i++) {
        o[i] = ts_dvec3_to_vec3(ts_xform_point(&x, ts_dvec3_from(o[i])));
        d[i] = ts_dvec3_to_vec3(ts_xform_vector(&x, ts_dvec3_from(d[i])));
    }
}

float ts_camera_time(const ts_camera *cam, float u)
{
    return ts_lerpf(u, cam->shutter_open, cam->shutter_close);
}
