/* The rig's bushing as a C spec: an 8-point spline backbone, 4 Maxwell
 * cells (exact ramp) and 3 Jenkins cells (clamp form), at 5 kHz. The
 * values of scenes/rig-loop.toml and of the Rust rig loop
 * (board-examples/src/rig/mod.rs, rig_bushing). */
#ifndef RIG_SPEC_H
#define RIG_SPEC_H

#include "bushing.h"

#define RIG_RATE_HZ 5000.0

static inline bushing_spec_t rig_spec(void)
{
    bushing_spec_t s = {0};
    static const double x[8] = {-4.0, -2.0, -1.0, 0.0, 0.5, 1.0, 2.0, 4.0};
    static const double f[8] = {-2500.0, -700.0, -250.0, 0.0, 110.0, 240.0, 600.0, 1900.0};
    static const double hz[4] = {0.05, 0.5, 5.0, 50.0};
    static const double g[4] = {0.1, 0.1, 0.15, 0.1};
    static const double slip[3] = {0.6, 2.4, 6.0};
    s.dt_s = 1.0 / RIG_RATE_HZ;
    s.backbone = BUSHING_BACKBONE_SPLINE;
    s.points = 8;
    for (int i = 0; i < 8; i++) {
        s.x_mm[i] = x[i];
        s.force_n[i] = f[i];
    }
    s.maxwell_form = BUSHING_MAXWELL_RATE_EXACT_RAMP;
    s.maxwell_cells = 4;
    for (int i = 0; i < 4; i++) {
        s.maxwell_hz[i] = hz[i];
        s.maxwell_g[i] = g[i];
    }
    s.iwan_cells = 3;
    for (int i = 0; i < 3; i++) {
        s.iwan_g[i] = 0.08;
        s.iwan_slip_n[i] = slip[i];
    }
    return s;
}

#endif /* RIG_SPEC_H */
