// Resampling MIS weights m_i(y): the GLSL twin of restir/src/mis.rs. Index 0 is the receiver
// (canonical) domain, 1..n-1 the neighbours; targets[j] = p̂_{<-j}(y), confidences[j] = c_j,
// only the first `n` entries are read. Sums run left to right from 0 like Rust's `Iterator::sum`.

#ifndef RESTIR_MIS_GLSL
#define RESTIR_MIS_GLSL

// MAX_DOMAINS and the MisKind codes MIS_<KIND> with their list MIS_KINDS(X).
#include "contract/restir.glsl"

// `num / den`, 0 when `den` is not positive.
float mis_ratio(float num, float den) {
    precise float q = num / den;
    return den > 0.0 ? q : 0.0;
}

// Generalized balance heuristic with confidences: m_i = c_i p̂_{<-i} / Σ_j c_j p̂_{<-j} [001 Eq. 8].
float mis_gbh_weight(uint i, float targets[MAX_DOMAINS], float confidences[MAX_DOMAINS], uint n) {
    precise float den = 0.0;
    for (uint j = 0u; j < n; j++) {
        precise float term = confidences[j] * targets[j];
        den = den + term;
    }
    precise float num = confidences[i] * targets[i];
    return mis_ratio(num, den);
}

// Pairwise MIS with confidences: m_i = a_i / (a_i + b) / k, m_c = Σ_i b / (a_i + b) / k with
// a_i = c_i p̂_{<-i}, b = c_c p̂_c; 1 without neighbours.
float mis_pairwise_weight(uint i, float targets[MAX_DOMAINS], float confidences[MAX_DOMAINS],
                          uint n) {
    uint k = n - 1u;
    if (k == 0u) {
        return 1.0;
    }
    precise float b = confidences[0] * targets[0];
    if (i == 0u) {
        precise float pairs = 0.0;
        for (uint j = 1u; j <= k; j++) {
            precise float a = confidences[j] * targets[j];
            precise float ab = a + b;
            precise float share = b / ab;
            pairs = pairs + (ab > 0.0 ? share : 1.0);
        }
        precise float m = pairs / float(k);
        return m;
    }
    precise float a = confidences[i] * targets[i];
    precise float m = mis_ratio(a, a + b) / float(k);
    return m;
}

// Defensive pairwise MIS (DESIGN §9): b = c_c p̂_c / v; m_i = a_i / (a_i + b) / (v + 1),
// m_c = [1 + Σ_i b / (b + a_i)] / (v + 1); 1 without neighbours.
float mis_defensive_pairwise_weight(uint i, float targets[MAX_DOMAINS],
                                    float confidences[MAX_DOMAINS], uint n) {
    uint v = n - 1u;
    if (v == 0u) {
        return 1.0;
    }
    precise float b = confidences[0] * targets[0] / float(v);
    precise float share = 1.0 / (float(v) + 1.0);
    if (i == 0u) {
        precise float pairs = 0.0;
        for (uint j = 1u; j <= v; j++) {
            precise float a = confidences[j] * targets[j];
            precise float ab = a + b;
            precise float ba = b + a;
            precise float part = b / ba;
            pairs = pairs + (ab > 0.0 ? part : 1.0);
        }
        precise float m = (1.0 + pairs) * share;
        return m;
    }
    precise float a = confidences[i] * targets[i];
    precise float m = mis_ratio(a, a + b) * share;
    return m;
}

// m_i = c_i / Σ_j c_j ("1/M" with confidences; biased unless supports agree).
float mis_confidence_only_weight(uint i, float targets[MAX_DOMAINS],
                                 float confidences[MAX_DOMAINS], uint n) {
    precise float sum = 0.0;
    for (uint j = 0u; j < n; j++) {
        sum = sum + confidences[j];
    }
    return mis_ratio(confidences[i], sum);
}

// MisScheme::needs_all_targets of each scheme: GBH reads every target, the pairwise schemes
// every target only for the canonical sample, 1/M none.
bool mis_gbh_needs_all_targets(uint i) {
    return true;
}

bool mis_pairwise_needs_all_targets(uint i) {
    return i == 0u;
}

bool mis_defensive_pairwise_needs_all_targets(uint i) {
    return i == 0u;
}

bool mis_confidence_only_needs_all_targets(uint i) {
    return false;
}

// MisScheme::needs_all_targets of scheme `kind` (a MisKind code).
bool mis_needs_all_targets(uint kind, uint i) {
#define MIS_NEEDS_ALL_TARGETS(KIND, stem) \
    if (kind == KIND) { \
        return mis_##stem##_needs_all_targets(i); \
    }
    MIS_KINDS(MIS_NEEDS_ALL_TARGETS)
#undef MIS_NEEDS_ALL_TARGETS
    return false;
}

// MisScheme::weight of scheme `kind` (a MisKind code; the host sends no other, see
// PassParams::new).
float mis_weight(uint kind, uint i, float targets[MAX_DOMAINS], float confidences[MAX_DOMAINS],
                 uint n) {
#define MIS_WEIGHT(KIND, stem) \
    if (kind == KIND) { \
        return mis_##stem##_weight(i, targets, confidences, n); \
    }
    MIS_KINDS(MIS_WEIGHT)
#undef MIS_WEIGHT
    return 0.0;
}

#endif
