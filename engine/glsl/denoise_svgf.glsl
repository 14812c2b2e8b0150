#version 460
// The spatiotemporal variance-guided filter [SVGF] per pixel: the GLSL twin of
// engine/src/denoise/svgf/stages.rs (read the two side by side; one function per function, the
// same operation order, every result `precise`, no fma). The host (engine/src/vulkan/svgf.rs)
// dispatches, per frame, stage SVGF_STAGE_TEMPORAL, SVGF_STAGE_VARIANCE and one SVGF_STAGE_ATROUS
// per iteration (ping-ponging bindings 4 and 5); demodulation, the depth gradients and
// remodulation are done on the host. Only exp() (the edge-stopping weights) is not bit-identical
// to the CPU's.
//
// Bindings: 0 SvgfPixel per pixel, 1 vec4 demodulated frame, 2 SvgfHistory read (the previous
// frame's in the temporal stage, the current one in the variance stage), 3 SvgfHistory of the
// current frame (written by the temporal stage and by the feedback iteration's colour),
// 4 vec4 filter input, 5 vec4 filter output (rgb colour, w variance), 6 uint loops-cut counter.
// Push constants: SvgfParams.

layout(local_size_x = 64) in;

#include "contract/svgf_params.glsl"
#include "contract/engine.glsl"
#include "frame.glsl"
#include "loop_budget.glsl"

layout(std430, binding = 0) readonly buffer Pixels { SvgfPixel pixels[]; };
layout(std430, binding = 1) readonly buffer FrameColour { vec4 frame_colour[]; };
layout(std430, binding = 2) readonly buffer HistoryIn { SvgfHistory history_in[]; };
layout(std430, binding = 3) buffer HistoryOut { SvgfHistory history_out[]; };
layout(std430, binding = 4) readonly buffer FilterIn { vec4 filter_in[]; };
layout(std430, binding = 5) writeonly buffer FilterOut { vec4 filter_out[]; };
layout(std430, binding = 6) buffer Cut { uint cut; };

// sss::color::luminance.
float svgf_luminance(vec3 c) {
    return glam_dot(c, vec3(0.2126, 0.7152, 0.0722));
}

vec3 pixel_normal(uint p) {
    return vec3(pixels[p].normal[0], pixels[p].normal[1], pixels[p].normal[2]);
}

// Size::offset: the pixel (x + dx, y + dy) of p, false outside the image.
bool svgf_offset(uint p, int dx, int dy, out uint q) {
    int x = int(p % params.width) + dx;
    int y = int(p / params.width) + dy;
    q = uint(y) * params.width + uint(x);
    return x >= 0 && x < int(params.width) && y >= 0 && y < int(params.height);
}

// stages::reprojected: the previous frame's history through the 2×2 bilinear footprint of
// Schied et al. 2017 [SVGF §4.1], the kept taps' weights renormalised; false where none is kept.
bool svgf_reprojected(SvgfPixel pixel, out SvgfHistory r) {
    r.colour = float[3](0.0, 0.0, 0.0);
    r.moments = float[2](0.0, 0.0);
    r.frames = 0u;
    if (pixel.taps == 0u) {
        return false;
    }
    vec2 position = vec2(pixel.previous[0], pixel.previous[1]);
    vec2 corner = floor(position);
    precise float fx = position.x - corner.x;
    precise float fy = position.y - corner.y;
    precise float gx = 1.0 - fx;
    precise float gy = 1.0 - fy;
    precise float weights[4] = float[4](gx * gy, fx * gy, gx * fy, fx * fy);
    precise vec3 colour = vec3(0.0);
    precise float m1 = 0.0;
    precise float m2 = 0.0;
    precise float frames = 0.0;
    precise float sum = 0.0;
    for (uint t = 0u; t < 4u; t++) {
        int x = int(corner.x) + int(t & 1u);
        int y = int(corner.y) + int(t >> 1u);
        bool inside = x >= 0 && x < int(params.width) && y >= 0 && y < int(params.height);
        if (((pixel.taps >> t) & 1u) == 0u || !inside) {
            continue;
        }
        SvgfHistory h = history_in[uint(y) * params.width + uint(x)];
        if (h.frames == 0u) {
            continue;
        }
        precise float w = weights[t];
        colour = colour + vec3(h.colour[0], h.colour[1], h.colour[2]) * w;
        m1 = m1 + h.moments[0] * w;
        m2 = m2 + h.moments[1] * w;
        frames = frames + float(h.frames) * w;
        sum = sum + w;
    }
    if (!(sum > 0.0)) {
        return false;
    }
    precise vec3 c = colour / vec3(sum);
    precise float a = m1 / sum;
    precise float b = m2 / sum;
    precise float n = floor(frames / sum + 0.5);
    r.colour = float[3](c.x, c.y, c.z);
    r.moments = float[2](a, b);
    r.frames = uint(n);
    return true;
}

// stages::temporal.
SvgfHistory svgf_temporal(uint p, vec3 c) {
    precise float l = svgf_luminance(c);
    SvgfPixel pixel = pixels[p];
    SvgfHistory h;
    bool has = pixel.object != NO_PIXEL && svgf_reprojected(pixel, h);
    SvgfHistory out_h;
    if (!has) {
        out_h.colour = float[3](c.x, c.y, c.z);
        precise float l2 = l * l;
        out_h.moments = float[2](l, l2);
        out_h.frames = pixel.object != NO_PIXEL ? 1u : 0u;
        return out_h;
    }
    uint frames = h.frames == NO_PIXEL ? NO_PIXEL : h.frames + 1u;
    precise float alpha = max(1.0 / float(frames), params.alpha_colour);
    precise float beta = 1.0 - alpha;
    vec3 previous = vec3(h.colour[0], h.colour[1], h.colour[2]);
    precise vec3 colour = c * alpha + previous * beta;
    precise float a = params.alpha_moments;
    precise float b = 1.0 - a;
    precise float m1 = l * a + h.moments[0] * b;
    precise float m2 = (l * l) * a + h.moments[1] * b;
    out_h.colour = float[3](colour.x, colour.y, colour.z);
    out_h.moments = float[2](m1, m2);
    out_h.frames = frames;
    return out_h;
}

// stages::powi.
float svgf_powi(float x, uint n) {
    precise float result = 1.0;
    precise float base = x;
    uint e = n;
    while (e > 0u) {
        if ((e & 1u) == 1u) {
            result = result * base;
        }
        base = base * base;
        e = e >> 1u;
    }
    return result;
}

// stages::normal_weight.
float svgf_normal_weight(uint p, uint q) {
    precise float d = glam_dot(pixel_normal(p), pixel_normal(q));
    return svgf_powi(max(d, 0.0), params.sigma_normal);
}

// stages::depth_term.
float svgf_depth_term(uint p, uint q, float dx, float dy) {
    precise float along = abs(pixels[p].gradient[0] * dx + pixels[p].gradient[1] * dy);
    precise float t = abs(pixels[p].depth - pixels[q].depth)
        / (params.sigma_depth * along + params.epsilon_depth);
    return t;
}

// stages::variance (reads the current frame's history from binding 2).
float svgf_variance(uint p) {
    if (pixels[p].object == NO_PIXEL) {
        return 0.0;
    }
    SvgfHistory h = history_in[p];
    if (h.frames >= params.variance_history) {
        precise float v = h.moments[1] - h.moments[0] * h.moments[0];
        return max(v, 0.0);
    }
    int r = int(params.variance_radius);
    precise float m1 = 0.0;
    precise float m2 = 0.0;
    precise float sum = 0.0;
    for (int dy = -r; dy <= r; dy++) {
        for (int dx = -r; dx <= r; dx++) {
            uint q;
            if (!svgf_offset(p, dx, dy, q) || pixels[q].object != pixels[p].object) {
                continue;
            }
            precise float w = 1.0;
            if (q != p) {
                precise float e = svgf_depth_term(p, q, float(dx), float(dy));
                w = svgf_normal_weight(p, q) * exp(-e);
            }
            m1 = m1 + history_in[q].moments[0] * w;
            m2 = m2 + history_in[q].moments[1] * w;
            sum = sum + w;
        }
    }
    precise float a = m1 / sum;
    precise float b = m2 / sum;
    precise float v = b - a * a;
    return max(v, 0.0);
}

// stages::prefiltered_variance.
float svgf_prefiltered_variance(uint p) {
    const float G[3] = float[3](0.25, 0.5, 0.25);
    precise float sum = 0.0;
    precise float weight = 0.0;
    for (int dy = -1; dy <= 1; dy++) {
        for (int dx = -1; dx <= 1; dx++) {
            uint q;
            if (!svgf_offset(p, dx, dy, q)) {
                continue;
            }
            precise float k = G[dx + 1] * G[dy + 1];
            sum = sum + filter_in[q].w * k;
            weight = weight + k;
        }
    }
    precise float v = sum / weight;
    return v;
}

// stages::atrous.
vec4 svgf_atrous(uint p) {
    const float H[5] = float[5](1.0 / 16.0, 0.25, 0.375, 0.25, 1.0 / 16.0);
    if (pixels[p].object == NO_PIXEL) {
        return vec4(filter_in[p].xyz, 0.0);
    }
    precise float l = svgf_luminance(filter_in[p].xyz);
    precise float phi = params.sigma_luminance * sqrt(svgf_prefiltered_variance(p))
        + params.epsilon_luminance;
    precise vec3 colour = vec3(0.0);
    precise float variance = 0.0;
    precise float sum = 0.0;
    int step = int(params.step);
    for (int j = -2; j <= 2; j++) {
        for (int i = -2; i <= 2; i++) {
            int dx = i * step;
            int dy = j * step;
            uint q;
            if (!svgf_offset(p, dx, dy, q) || pixels[q].object != pixels[p].object) {
                continue;
            }
            precise float w = 1.0;
            if (q != p) {
                precise float e = svgf_depth_term(p, q, float(dx), float(dy))
                    + abs(l - svgf_luminance(filter_in[q].xyz)) / phi;
                w = svgf_normal_weight(p, q) * exp(-e);
            }
            precise float k = H[i + 2] * H[j + 2] * w;
            colour = colour + filter_in[q].xyz * k;
            variance = variance + filter_in[q].w * (k * k);
            sum = sum + k;
        }
    }
    precise vec3 c = colour / vec3(sum);
    precise float v = variance / (sum * sum);
    return vec4(c, v);
}

void main() {
    uint p = gl_GlobalInvocationID.x;
    uint count = params.width * params.height;
    if (p >= count) {
        return;
    }
    if (params.stage == SVGF_STAGE_TEMPORAL) {
        history_out[p] = svgf_temporal(p, frame_colour[p].xyz);
    } else if (params.stage == SVGF_STAGE_VARIANCE) {
        SvgfHistory h = history_in[p];
        filter_out[p] = vec4(h.colour[0], h.colour[1], h.colour[2], svgf_variance(p));
    } else {
        vec4 f = svgf_atrous(p);
        filter_out[p] = f;
        if (params.feedback != 0u) {
            history_out[p].colour = float[3](f.x, f.y, f.z);
        }
    }
    if (!loop_budget_intact(min(params.width, 1u))) {
        atomicAdd(cut, 1u);
    }
}
