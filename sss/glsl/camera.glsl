// Twin of sss::scene::Camera (sss/src/scene/camera.rs) at one frame. The host fills GpuCamera
// from the Camera's own methods (eye, forward, right_up, jitter), so the trajectory's lerp and
// normalisations and the Halton jitter are computed once on the CPU, bit for bit.

#ifndef SSS_CAMERA_GLSL
#define SSS_CAMERA_GLSL

#include "frame.glsl"

// GpuCamera (engine/src/contract.rs).
#include "contract/engine.glsl"

vec3 camera_eye(GpuCamera c) {
    return vec3(c.eye[0], c.eye[1], c.eye[2]);
}

vec3 camera_forward(GpuCamera c) {
    return vec3(c.forward[0], c.forward[1], c.forward[2]);
}

vec3 camera_right(GpuCamera c) {
    return vec3(c.right[0], c.right[1], c.right[2]);
}

vec3 camera_up(GpuCamera c) {
    return vec3(c.up[0], c.up[1], c.up[2]);
}

// Camera::pixels_per_unit: pixels per world unit on the image plane at view depth z.
float camera_pixels_per_unit(GpuCamera c, float z) {
    precise float k = float(c.height) / (2.0 * c.tan_half_fov * z);
    return k;
}

// Camera::ray: the primary ray through the jittered centre of pixel (px, py); its unit
// direction (t in (0, inf)), origin at the eye.
void camera_ray(GpuCamera c, uint px, uint py, out vec3 origin, out vec3 dir) {
    precise float pixel_x = (float(px) + 0.5) + c.jitter[0];
    precise float pixel_y = (float(py) + 0.5) + c.jitter[1];
    float w = float(c.width);
    float h = float(c.height);
    precise float sx = (2.0 * pixel_x - w) / h * c.tan_half_fov;
    precise float sy = (h - 2.0 * pixel_y) / h * c.tan_half_fov;
    precise vec3 d = camera_forward(c) + sx * camera_right(c) + sy * camera_up(c);
    origin = camera_eye(c);
    dir = glam_normalize(d);
}

// Camera::project: continuous pixel coordinates of p (no jitter); false behind the eye or
// outside [0, width) x [0, height).
bool camera_project(GpuCamera c, vec3 p, out vec2 pixel) {
    pixel = vec2(0.0);
    precise vec3 d = p - camera_eye(c);
    float z = glam_dot(d, camera_forward(c));
    if (!rust_is_finite(z) || z <= 0.0) {
        return false;
    }
    float k = camera_pixels_per_unit(c, z);
    float w = float(c.width);
    float h = float(c.height);
    precise float cx = 0.5 * w + glam_dot(d, camera_right(c)) * k;
    precise float cy = 0.5 * h - glam_dot(d, camera_up(c)) * k;
    if (cx >= 0.0 && cx < w && cy >= 0.0 && cy < h) {
        pixel = vec2(cx, cy);
        return true;
    }
    return false;
}

// Camera::spatial_radius_px: 2 max_d pixels_per_unit(z) clamped to [5, 30]; 5 behind the eye.
float camera_spatial_radius_px(GpuCamera c, vec3 x1, float max_d) {
    precise vec3 d = x1 - camera_eye(c);
    float z = glam_dot(d, camera_forward(c));
    precise float r = 2.0 * max_d * camera_pixels_per_unit(c, z);
    if (z > 0.0 && rust_is_finite(r)) {
        return rust_clamp(r, 5.0, 30.0);
    }
    return 5.0;
}

#endif
