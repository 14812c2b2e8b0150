// The frame radius of a reciprocal spatial pass: the GLSL twin of engine::reciprocal::frame_radius
// with RadiusRule::Clamped (engine/src/reciprocal.rs), the mean of Camera::spatial_radius_px over
// the pixels that show a translucent object. Each radius is `+ × ÷` of host-computed camera
// quantities (bit for bit the CPU's), and the sum runs in f64 in pixel order like the CPU's, so
// the mean is the CPU's bit for bit; one invocation computes it.
//
// The including kernel includes scene.glsl first, declares the G-buffer `gpixels` and enables
// GL_EXT_shader_explicit_arithmetic_types_int64 and shaderFloat64.

#ifndef ENGINE_FRAME_RADIUS_GLSL
#define ENGINE_FRAME_RADIUS_GLSL

// frame_radius: the mean radius over the frame's translucent pixels (their domains, as
// PassInput::domain builds them for pass `pass`), 0 where there is none.
float reciprocal_frame_radius(uint pass) {
    uint pixels = frame_params.width * frame_params.height;
    uint frame = frame_params.frame;
    uint64_t seed = scene_seed();
    double sum = 0.0lf;
    uint count = 0u;
    for (uint pixel = 0u; pixel < pixels; pixel++) {
        GPixel g = gpixels[pixel];
        SssDomain domain;
        if (!domain_new(g, pixel, frame, pass, seed, domain)) {
            continue;
        }
        float max_d = bssrdf_max_element(material_d(domain.material));
        float radius = camera_spatial_radius_px(
            frame_params.camera, vec3(g.position[0], g.position[1], g.position[2]), max_d);
        precise double next = sum + double(radius);
        sum = next;
        count += 1u;
    }
    if (count == 0u) {
        return 0.0;
    }
    precise double mean = sum / double(count);
    return float(mean);
}

#endif
