// The twin of sss::scene::GBuffer::reproject (sss/src/scene/gbuffer.rs): the pixel of an earlier
// frame that shows a later frame's primary hit. The including kernel defines
//   GPixel gbuffer_fetch_earlier(uint pixel);   // the earlier frame's G-buffer
// (declared below). Include after scene.glsl.

#ifndef SSS_GBUFFER_GLSL
#define SSS_GBUFFER_GLSL

// REPROJECTION_DEPTH_TOLERANCE, REPROJECTION_NORMAL_COSINE.
const float GBUFFER_REPROJECTION_DEPTH_TOLERANCE = 0.1;
const float GBUFFER_REPROJECTION_NORMAL_COSINE = 0.9;

GPixel gbuffer_fetch_earlier(uint pixel);

// GBuffer::reproject: floor(project(earlier camera, x1)), accepted if it shows the same object at
// a view distance within 10% and with geometric normals of cosine >= 0.9; false otherwise.
bool gbuffer_reproject(GpuCamera earlier_camera, GPixel x, out uint q) {
    q = 0u;
    vec3 position = vec3(x.position[0], x.position[1], x.position[2]);
    vec2 c;
    if (!camera_project(earlier_camera, position, c)) {
        return false;
    }
    uint qx = uint(c.x);
    uint qy = uint(c.y);
    if (qx >= earlier_camera.width || qy >= earlier_camera.height) {
        return false;
    }
    GPixel earlier = gbuffer_fetch_earlier(qy * earlier_camera.width + qx);
    if (earlier.valid == 0u) {
        return false;
    }
    float depth = glam_length(position - camera_eye(earlier_camera));
    precise float depth_error = abs(earlier.depth - depth);
    precise float depth_bound = GBUFFER_REPROJECTION_DEPTH_TOLERANCE * depth;
    vec3 n_earlier = vec3(earlier.geometric_normal[0], earlier.geometric_normal[1],
        earlier.geometric_normal[2]);
    vec3 n = vec3(x.geometric_normal[0], x.geometric_normal[1], x.geometric_normal[2]);
    bool same_surface = earlier.object == x.object && depth_error <= depth_bound
        && glam_dot(n_earlier, n) >= GBUFFER_REPROJECTION_NORMAL_COSINE;
    q = qy * earlier_camera.width + qx;
    return same_surface;
}

#endif
