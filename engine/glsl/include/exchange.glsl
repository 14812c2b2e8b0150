// Phase 1 of a reciprocal spatial pass at one pixel and slot: the GLSL twin of
// engine::reciprocal::shift_to_partners (engine/src/reciprocal.rs; read the two side by side),
// which shifts the pixel's sample into its partner of every slot. The shift of one destination
// is the CPU's Shift::shift_with_targets (a shift's batched shifts_with_targets agrees with it).
//
// The including kernel includes scene.glsl, shift.glsl and include/reciprocal.glsl first and
// declares the G-buffer `gpixels`.

#ifndef ENGINE_EXCHANGE_GLSL
#define ENGINE_EXCHANGE_GLSL

// EXCHANGE_* (engine::contract::ExchangeStatus).
#include "contract/engine.glsl"

// Exchanged::Sent's values: y = T(x) in the partner, J, p̂_partner(y) and p̂_own(x).
struct Sent {
    SssSample y;
    float jacobian;
    float target;
    float source_target;
};

// partner: the pixel index and domain of `source`'s partner in `pairing` (paired: the slot is
// not empty) when the pair is taken, inside the image and on the same translucent object.
bool exchange_partner(SssDomain source, uint object, bool paired, Pairing pairing,
                      out uint q, out SssDomain partner) {
    q = 0u;
    if (!paired) {
        return false;
    }
    int width = int(frame_params.width);
    int height = int(frame_params.height);
    ivec2 p = ivec2(int(source.pixel) % width, int(source.pixel) / width);
    ivec2 other = pairing_partner(pairing, p);
    if (!(other.x >= 0 && other.y >= 0 && other.x < width && other.y < height)) {
        return false;
    }
    q = uint(other.y * width + other.x);
    GPixel g = gpixels[q];
    if (!domain_new(g, q, source.frame, source.pass, source.seed, partner)) {
        return false;
    }
    partner.target = source.target;
    return g.object == object;
}

// shift_to_partners for one slot: what `source` (on `object`, with the stored reservoir
// `stored`) sends its partner, an EXCHANGE_* status, and `sent` when it is EXCHANGE_SENT.
uint exchange_send(SssDomain source, uint object, PixelReservoir stored, bool paired,
                   Pairing pairing, uint shift_kind, out Sent sent) {
    sent.y = reservoir_empty().y;
    sent.jacobian = 0.0;
    sent.target = 0.0;
    sent.source_target = 0.0;
    uint q;
    SssDomain partner;
    if (!exchange_partner(source, object, paired, pairing, q, partner)) {
        return EXCHANGE_UNTAKEN;
    }
    if (stored.has_sample == 0u || !(stored.ucw > 0.0)) {
        return EXCHANGE_UNSHIFTED;
    }
    ShiftSpec spec = shift_spec(shift_kind, source.material);
    uint fail = shift_shift(spec, stored.y, source, partner, sent.y, sent.jacobian);
    if (fail != SHIFT_OK) {
        sent.y = reservoir_empty().y;
        sent.jacobian = 0.0;
        return EXCHANGE_FAILED | (fail << 8);
    }
    sent.target = domain_target(partner, sent.y);
    sent.source_target = domain_target(source, stored.y);
    return EXCHANGE_SENT;
}

#endif
