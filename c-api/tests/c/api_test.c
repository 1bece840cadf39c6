/* Host test of the C API: every entry point of bushing.h, every status
 * code, the rig bushing in f32 and Q16, every optional effect and the
 * two trackers.
 * Built and run by scripts/c-api.sh (gcc, linked with the host
 * staticlib); exits 0 when every check holds. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bushing.h"
#include "rig_spec.h"

static int failures = 0;
static int checks = 0;

#define CHECK(cond)                                                                    \
    do {                                                                               \
        checks++;                                                                      \
        if (!(cond)) {                                                                 \
            failures++;                                                                \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond);   \
        }                                                                              \
    } while (0)

#define Q16_ONE 65536.0

static int32_t to_q16(double v) { return (int32_t)lrint(v * Q16_ONE); }
static double from_q16(int32_t v) { return (double)v / Q16_ONE; }

/* init of `spec` in f32 must fail with `status`, naming `param` (and
 * `index`, -1 for none). */
static void refused(const bushing_spec_t *spec, bushing_status_t status, const char *param,
                    int index)
{
    static bushing_f32_t model;
    bushing_error_t e;
    memset(&e, 0xff, sizeof e);
    bushing_status_t got = bushing_f32_init(&model, spec, &e);
    CHECK(got == status);
    CHECK(e.status == status);
    CHECK(strcmp(e.param, param) == 0);
    CHECK(e.index == index);
    if (got != status || strcmp(e.param, param) != 0) {
        fprintf(stderr, "  got %s (%d) param '%s'[%d], expected %s '%s'\n",
                bushing_status_name(got), got, e.param, e.index, bushing_status_name(status),
                param);
    }
    /* The same spec in Q16 is refused with the same code, and the
     * error detail is optional. */
    static bushing_q16_t q;
    CHECK(bushing_q16_init(&q, spec, NULL) == status);
}

static void every_refusal(void)
{
    const bushing_spec_t rig = rig_spec();
    bushing_spec_t s;

    s = rig; s.backbone = 7;
    refused(&s, BUSHING_STATUS_UNKNOWN_KIND, "backbone", -1);
    s = rig; s.maxwell_form = 5;
    refused(&s, BUSHING_STATUS_UNKNOWN_KIND, "maxwell_form", -1);
    s = rig; s.xf_cells = 1; s.xf_form = 2; s.xf_g[0] = 0.1; s.xf_distance_mm[0] = 0.5;
    refused(&s, BUSHING_STATUS_UNKNOWN_KIND, "xf_form", -1);
    s = rig; s.sts = 3;
    refused(&s, BUSHING_STATUS_UNKNOWN_KIND, "sts", -1);
    s = rig; s.friction = 4;
    refused(&s, BUSHING_STATUS_UNKNOWN_KIND, "friction", -1);

    s = rig; s.x_mm[2] = NAN;
    refused(&s, BUSHING_STATUS_NOT_FINITE, "x_mm", 2);
    s = rig; s.dt_s = 0.0;
    refused(&s, BUSHING_STATUS_NOT_POSITIVE, "dt_s", -1);
    s = rig; s.maxwell_g[0] = 0.5; s.maxwell_g[1] = 0.5;
    refused(&s, BUSHING_STATUS_FRACTIONS_ABOVE_ONE, "g", -1);
    s = rig; s.maxwell_g[3] = 1.5;
    refused(&s, BUSHING_STATUS_CELL_FRACTION_ABOVE_ONE, "maxwell_g", 3);
    s = rig; s.maxwell_form = BUSHING_MAXWELL_LOAD_EXPLICIT; s.maxwell_hz[3] = 2000.0;
    refused(&s, BUSHING_STATUS_EXPLICIT_UNSTABLE, "maxwell_hz", 3);
    s = rig; s.points = 1;
    refused(&s, BUSHING_STATUS_TOO_FEW, "x_mm", -1);
    s = rig; s.maxwell_cells = BUSHING_MAX_MAXWELL + 1;
    refused(&s, BUSHING_STATUS_TOO_MANY, "maxwell_cells", -1);
    s = rig; s.x_mm[5] = s.x_mm[4];
    refused(&s, BUSHING_STATUS_NOT_INCREASING, "x_mm", 5);
    s = rig; s.backbone = BUSHING_BACKBONE_POLYNOMIAL; s.points = 2;
    s.force_n[0] = 0.0; s.force_n[1] = -150.0; s.range_mm[0] = -6.0; s.range_mm[1] = 6.0;
    refused(&s, BUSHING_STATUS_TANGENT_NOT_POSITIVE, "", -1);
    s.force_n[1] = 150.0; s.range_mm[1] = -6.0;
    refused(&s, BUSHING_STATUS_EMPTY_RANGE, "", -1);
    s = rig; s.friction = BUSHING_FRICTION_BERG; s.friction_params[0] = 40.0;
    s.friction_params[1] = 1e-40;
    refused(&s, BUSHING_STATUS_OUT_OF_RANGE, "friction_params", 1);

    /* The error detail: value and bound. */
    static bushing_f32_t model;
    bushing_error_t e;
    s = rig; s.iwan_cells = 20;
    CHECK(bushing_f32_init(&model, &s, &e) == BUSHING_STATUS_TOO_MANY);
    CHECK(e.value == 20.0 && e.bound == (double)BUSHING_MAX_IWAN);
}

/* Every code has its name; the codes no spec of this API reaches (a
 * length mismatch, an increasing K_f table, two time steps) too. */
static void every_name(void)
{
    static const struct {
        bushing_status_t code;
        const char *name;
    } codes[] = {
#define CODE(c) {c, #c}
        CODE(BUSHING_STATUS_OK), CODE(BUSHING_STATUS_REFUSED), CODE(BUSHING_STATUS_NULL_POINTER),
        CODE(BUSHING_STATUS_NOT_INITIALISED), CODE(BUSHING_STATUS_UNKNOWN_KIND),
        CODE(BUSHING_STATUS_NOT_FINITE), CODE(BUSHING_STATUS_NOT_POSITIVE),
        CODE(BUSHING_STATUS_FRACTIONS_ABOVE_ONE), CODE(BUSHING_STATUS_CELL_FRACTION_ABOVE_ONE),
        CODE(BUSHING_STATUS_EXPLICIT_UNSTABLE), CODE(BUSHING_STATUS_TOO_FEW),
        CODE(BUSHING_STATUS_TOO_MANY), CODE(BUSHING_STATUS_LENGTH_MISMATCH),
        CODE(BUSHING_STATUS_NOT_INCREASING), CODE(BUSHING_STATUS_INCREASING),
        CODE(BUSHING_STATUS_TANGENT_NOT_POSITIVE), CODE(BUSHING_STATUS_EMPTY_RANGE),
        CODE(BUSHING_STATUS_OUT_OF_RANGE), CODE(BUSHING_STATUS_TIME_STEP_MISMATCH),
#undef CODE
    };
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++) {
        CHECK(strcmp(bushing_status_name(codes[i].code), codes[i].name) == 0);
    }
    CHECK(strcmp(bushing_status_name(12345), "BUSHING_STATUS_UNKNOWN") == 0);
}

/* Null pointers and storage that init or reset did not set. */
static void misuse(void)
{
    const bushing_spec_t rig = rig_spec();
    static bushing_f32_t model, blank;
    static bushing_f32_state_t state, blank_state;
    static bushing_q16_t qmodel;
    static bushing_q16_state_t qstate;
    bushing_f32_output_t out;
    bushing_q16_output_t qout;
    uint8_t flags;

    CHECK(bushing_f32_init(NULL, &rig, NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_f32_init(&model, NULL, NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_f32_init(&model, &rig, NULL) == BUSHING_STATUS_OK);
    CHECK(bushing_f32_reset(NULL, &state, 0.0f) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_f32_reset(&model, NULL, 0.0f) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_f32_reset(&blank, &state, 0.0f) == BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_f32_reset(&model, &state, 0.0f) == BUSHING_STATUS_OK);
    CHECK(bushing_f32_step(&model, &state, 0.1f, NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_f32_step(&model, &blank_state, 0.1f, &out) == BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_f32_step(&blank, &state, 0.1f, &out) == BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_f32_trial(&model, &state, 0.1f, NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_f32_trial(&model, &blank_state, 0.1f, &out) == BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_f32_faults(&state, NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_f32_faults(&blank_state, &flags) == BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_f32_clear_faults(NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_f32_clear_faults(&blank_state) == BUSHING_STATUS_NOT_INITIALISED);

    /* A Q16 model or state handed to the f32 functions is refused. */
    CHECK(bushing_q16_init(&qmodel, &rig, NULL) == BUSHING_STATUS_OK);
    CHECK(bushing_q16_reset(&qmodel, &qstate, 0) == BUSHING_STATUS_OK);
    CHECK(bushing_f32_step((const bushing_f32_t *)(const void *)&qmodel, &state, 0.1f, &out) ==
          BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_q16_step(&qmodel, (bushing_q16_state_t *)(void *)&state, 0, &qout) ==
          BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_q16_step(&qmodel, &qstate, 0, NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_q16_trial(NULL, &qstate, 0, &qout) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_q16_faults(NULL, &flags) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_q16_clear_faults(NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_q16_reset(NULL, &qstate, 0) == BUSHING_STATUS_NULL_POINTER);
}

/* The rig bushing in f32 and Q16 over a 2 mm, 10 Hz sine: finite forces
 * that agree, energy dissipated, trial equal to step, a refused NaN. */
static void rig_run(void)
{
    const bushing_spec_t rig = rig_spec();
    static bushing_f32_t model;
    static bushing_f32_state_t state;
    static bushing_q16_t qmodel;
    static bushing_q16_state_t qstate;
    bushing_f32_output_t out, tried;
    bushing_q16_output_t qout, qtried;
    uint8_t flags = 0xff;

    CHECK(bushing_f32_init(&model, &rig, NULL) == BUSHING_STATUS_OK);
    CHECK(bushing_q16_init(&qmodel, &rig, NULL) == BUSHING_STATUS_OK);
    CHECK(bushing_f32_reset(&model, &state, 0.0f) == BUSHING_STATUS_OK);
    CHECK(bushing_q16_reset(&qmodel, &qstate, 0) == BUSHING_STATUS_OK);
    double energy = 0.0, worst = 0.0, peak = 0.0;
    for (int n = 1; n <= 2000; n++) {
        double x = 2.0 * sin(2.0 * 3.141592653589793 * 10.0 * n / RIG_RATE_HZ);
        CHECK(bushing_f32_trial(&model, &state, (float)x, &tried) == BUSHING_STATUS_OK);
        CHECK(bushing_f32_step(&model, &state, (float)x, &out) == BUSHING_STATUS_OK);
        CHECK(memcmp(&tried, &out, sizeof out) == 0);
        CHECK(bushing_q16_trial(&qmodel, &qstate, to_q16(x), &qtried) == BUSHING_STATUS_OK);
        CHECK(bushing_q16_step(&qmodel, &qstate, to_q16(x), &qout) == BUSHING_STATUS_OK);
        CHECK(memcmp(&qtried, &qout, sizeof qout) == 0);
        CHECK(isfinite(out.force) && isfinite(out.tangent) && out.dissipated >= 0.0f);
        CHECK(out.tangent > 0.0f);
        energy += out.dissipated;
        double d = fabs(from_q16(qout.force) - out.force);
        worst = d > worst ? d : worst;
        peak = fabs(out.force) > peak ? fabs(out.force) : peak;
    }
    printf("rig bushing, 2000 steps of a 2 mm 10 Hz sine: peak %.1f N, dissipated %.1f mJ, "
           "|Q16 - f32| <= %.4f N\n",
           peak, energy, worst);
    CHECK(peak > 400.0 && peak < 700.0);
    CHECK(energy > 0.0);
    /* Q16 against f32: within a DAC step (1/8 N) of this 500 N swing. */
    CHECK(worst < 0.125);
    CHECK(bushing_f32_faults(&state, &flags) == BUSHING_STATUS_OK && flags == 0);

    /* A NaN is refused: the state kept, the flag raised, then cleared. */
    bushing_f32_output_t before = out;
    CHECK(bushing_f32_step(&model, &state, NAN, &out) == BUSHING_STATUS_REFUSED);
    CHECK(out.force == before.force && out.dissipated == 0.0f);
    CHECK(bushing_f32_faults(&state, &flags) == BUSHING_STATUS_OK);
    CHECK(flags == BUSHING_FAULT_NON_FINITE_INPUT);
    CHECK(bushing_f32_clear_faults(&state) == BUSHING_STATUS_OK);
    CHECK(bushing_f32_faults(&state, &flags) == BUSHING_STATUS_OK && flags == 0);
    /* Beyond the guard in Q16 (saturated): refused with OUT_OF_RANGE. */
    CHECK(bushing_q16_trial(&qmodel, &qstate, INT32_MAX, &qtried) == BUSHING_STATUS_REFUSED);
    CHECK(bushing_q16_step(&qmodel, &qstate, INT32_MAX, &qout) == BUSHING_STATUS_REFUSED);
    CHECK(bushing_q16_faults(&qstate, &flags) == BUSHING_STATUS_OK);
    CHECK(flags != 0);
    CHECK(bushing_q16_clear_faults(&qstate) == BUSHING_STATUS_OK);
    CHECK(bushing_q16_faults(&qstate, &flags) == BUSHING_STATUS_OK && flags == 0);

    /* reset puts the state back at rest: the first step repeats. */
    bushing_f32_output_t first, again;
    CHECK(bushing_f32_reset(&model, &state, 0.0f) == BUSHING_STATUS_OK);
    CHECK(bushing_f32_step(&model, &state, 0.25f, &first) == BUSHING_STATUS_OK);
    CHECK(bushing_f32_reset(&model, &state, 0.0f) == BUSHING_STATUS_OK);
    CHECK(bushing_f32_step(&model, &state, 0.25f, &again) == BUSHING_STATUS_OK);
    CHECK(memcmp(&first, &again, sizeof first) == 0);
}

/* Each optional effect alone on a polynomial backbone: a loop of 1 mm
 * dissipates energy and no fault is raised. */
static void each_effect(void)
{
    bushing_spec_t base = {0};
    base.dt_s = 1e-3;
    base.backbone = BUSHING_BACKBONE_POLYNOMIAL;
    base.points = 4;
    base.force_n[1] = 150.0;
    base.force_n[3] = 4.0;
    base.range_mm[0] = -6.0;
    base.range_mm[1] = 6.0;

    bushing_spec_t specs[6];
    const char *names[6] = {"x_f (exact ramp)", "STS (Masing)", "STS (first point a turn)",
                            "Dahl", "Bouc-Wen", "Berg"};
    for (int i = 0; i < 6; i++) specs[i] = base;
    specs[0].xf_form = BUSHING_XF_EXACT_RAMP;
    specs[0].xf_cells = 2;
    specs[0].xf_hz[0] = 1.0; specs[0].xf_g[0] = 0.1; specs[0].xf_distance_mm[0] = 0.2;
    specs[0].xf_hz[1] = 0.0; specs[0].xf_g[1] = 0.1; specs[0].xf_distance_mm[1] = 0.5;
    specs[1].sts = BUSHING_STS_MASING; specs[1].sts_c = 100.0; specs[1].sts_k1 = 40.0;
    specs[2].sts = BUSHING_STS_IGNORED; specs[2].sts_c = 100.0; specs[2].sts_k1 = 40.0;
    specs[3].friction = BUSHING_FRICTION_DAHL;
    specs[3].friction_params[0] = 60.0; specs[3].friction_params[1] = 8.0;
    specs[3].friction_params[2] = 1.0;
    specs[4].friction = BUSHING_FRICTION_BOUC_WEN;
    specs[4].friction_params[0] = 40.0; specs[4].friction_params[1] = 1.0;
    specs[4].friction_params[2] = 0.75; specs[4].friction_params[3] = 0.25;
    specs[4].friction_params[4] = 1.0;
    specs[5].friction = BUSHING_FRICTION_BERG;
    specs[5].friction_params[0] = 8.0; specs[5].friction_params[1] = 0.1;

    for (int i = 0; i < 6; i++) {
        static bushing_f32_t model;
        static bushing_f32_state_t state;
        bushing_error_t e;
        bushing_status_t st = bushing_f32_init(&model, &specs[i], &e);
        CHECK(st == BUSHING_STATUS_OK);
        if (st != BUSHING_STATUS_OK) {
            fprintf(stderr, "  %s: %s '%s'[%d]\n", names[i], bushing_status_name(st), e.param,
                    e.index);
            continue;
        }
        CHECK(bushing_f32_reset(&model, &state, 0.0f) == BUSHING_STATUS_OK);
        double energy = 0.0;
        bushing_f32_output_t out;
        for (int n = 1; n <= 2000; n++) {
            float x = (float)sin(2.0 * 3.141592653589793 * n / 1000.0);
            CHECK(bushing_f32_step(&model, &state, x, &out) == BUSHING_STATUS_OK);
            CHECK(isfinite(out.force));
            energy += out.dissipated;
        }
        uint8_t flags = 0xff;
        CHECK(bushing_f32_faults(&state, &flags) == BUSHING_STATUS_OK && flags == 0);
        CHECK(energy > 0.0);
        printf("%-26s two 1 mm cycles: dissipated %8.3f mJ\n", names[i], energy);
    }
}


/* The modal tracker, EKF and UKF, on a lightly damped 12 Hz decay
 * sampled at 1 kHz: the frequency and damping are found, trial equals
 * step, a NaN is refused, bad specs are refused by name. */
static void modal_tracker(void)
{
    for (uint32_t filter = BUSHING_FILTER_EKF; filter <= BUSHING_FILTER_UKF; filter++) {
        bushing_tracker_spec_t spec;
        CHECK(bushing_tracker_defaults(&spec) == BUSHING_STATUS_OK);
        spec.filter = filter;
        spec.dt_s = 1e-3;
        spec.noise = 1e-3;
        spec.frequency_hz = 11.5;
        spec.damping = 0.0;
        spec.amplitude[0] = 0.0;
        spec.amplitude[1] = -1.0;
        spec.initial_frequency_error = 0.05;
        static bushing_tracker_t tracker;
        static bushing_tracker_state_t state;
        CHECK(bushing_tracker_init(&tracker, &spec, NULL) == BUSHING_STATUS_OK);
        CHECK(bushing_tracker_reset(&tracker, &state) == BUSHING_STATUS_OK);
        bushing_tracker_report_t r, tried;
        const double f = 12.0, zeta = 0.02, w = 2.0 * 3.141592653589793 * f;
        for (int n = 0; n < 2000; n++) {
            double t = n * 1e-3;
            float x = (float)(exp(-zeta * w * t) * sin(w * sqrt(1.0 - zeta * zeta) * t));
            CHECK(bushing_tracker_trial(&tracker, &state, x, &tried) == BUSHING_STATUS_OK);
            CHECK(bushing_tracker_step(&tracker, &state, x, &r) == BUSHING_STATUS_OK);
            CHECK(memcmp(&tried, &r, sizeof r) == 0);
        }
        printf("modal tracker (%s), 12 Hz decay at 2 %%: %.4f Hz, damping %.4f\n",
               filter == BUSHING_FILTER_EKF ? "EKF" : "UKF", r.frequency_hz, r.damping);
        CHECK(fabs(r.frequency_hz - f) < 0.01 * f);
        CHECK(fabs(r.damping - zeta) < 0.005);
        CHECK(r.accepted == 1 && r.faded == 0);
        CHECK(bushing_tracker_step(&tracker, &state, NAN, &r) == BUSHING_STATUS_REFUSED);
        CHECK(r.refused == 1 && r.accepted == 0);
        bushing_tracker_counts_t c;
        CHECK(bushing_tracker_counts(&state, &c) == BUSHING_STATUS_OK);
        CHECK(c.outliers == 0 && c.repairs == 0 && c.reacquisitions == 0);
    }

    bushing_tracker_spec_t spec;
    bushing_tracker_defaults(&spec);
    static bushing_tracker_t tracker, blank;
    static bushing_tracker_state_t state, blank_state;
    bushing_error_t e;
    bushing_tracker_report_t r;
    bushing_tracker_counts_t c;
    spec.filter = 5;
    CHECK(bushing_tracker_init(&tracker, &spec, &e) == BUSHING_STATUS_UNKNOWN_KIND);
    CHECK(strcmp(e.param, "filter") == 0);
    bushing_tracker_defaults(&spec);
    spec.measured = 9;
    CHECK(bushing_tracker_init(&tracker, &spec, &e) == BUSHING_STATUS_UNKNOWN_KIND);
    CHECK(strcmp(e.param, "measured") == 0);
    bushing_tracker_defaults(&spec);
    spec.dt_s = -1.0;
    CHECK(bushing_tracker_init(&tracker, &spec, &e) == BUSHING_STATUS_NOT_POSITIVE);
    CHECK(strcmp(e.param, "dt") == 0 && e.value == -1.0);
    bushing_tracker_defaults(&spec);
    spec.filter = BUSHING_FILTER_UKF;
    spec.ut_alpha = 2.0;
    CHECK(bushing_tracker_init(&tracker, &spec, &e) == BUSHING_STATUS_OUT_OF_RANGE);
    CHECK(bushing_tracker_defaults(NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_tracker_init(&tracker, NULL, NULL) == BUSHING_STATUS_NULL_POINTER);
    bushing_tracker_defaults(&spec);
    CHECK(bushing_tracker_init(&tracker, &spec, NULL) == BUSHING_STATUS_OK);
    CHECK(bushing_tracker_reset(&blank, &state) == BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_tracker_reset(&tracker, NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_tracker_step(&tracker, &blank_state, 0.0f, &r) == BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_tracker_step(&tracker, &state, 0.0f, NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_tracker_trial(&blank, &state, 0.0f, &r) == BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_tracker_counts(&blank_state, &c) == BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_tracker_counts(NULL, &c) == BUSHING_STATUS_NULL_POINTER);
}

/* The on-line complex modulus of a 5 Hz test, F = 100 x + (20/w) dx/dt:
 * K' = 100 N/mm and K'' = 20 N/mm found; trial equals step; refusals. */
static void modulus_tracker(void)
{
    bushing_modulus_spec_t spec = {
        .dt_s = 1e-3,
        .frequency_hz = 5.0,
        .bandwidth_hz = 1.0,
        .displacement_noise = 1e-3,
        .displacement_amplitude = 1.0,
        .force_noise = 0.1,
        .force_amplitude = 100.0,
        .min_snr = 10.0,
    };
    static bushing_modulus_t tracker, blank;
    static bushing_modulus_state_t state, blank_state;
    bushing_modulus_value_t m, tried;
    bushing_error_t e;
    CHECK(bushing_modulus_init(&tracker, &spec, &e) == BUSHING_STATUS_OK);
    CHECK(bushing_modulus_reset(&tracker, &state) == BUSHING_STATUS_OK);
    const double w = 2.0 * 3.141592653589793 * 5.0;
    for (int n = 0; n < 3000; n++) {
        double t = n * 1e-3;
        float x = (float)sin(w * t);
        float f = (float)(100.0 * sin(w * t) + 20.0 * cos(w * t));
        CHECK(bushing_modulus_trial(&tracker, &state, x, f, &tried) == BUSHING_STATUS_OK);
        CHECK(bushing_modulus_step(&tracker, &state, x, f, &m) == BUSHING_STATUS_OK);
        CHECK(memcmp(&tried, &m, sizeof m) == 0);
    }
    printf("modulus tracker, 5 Hz: K' %.3f N/mm, K'' %.3f N/mm\n", m.storage, m.loss);
    CHECK(m.valid == 1);
    CHECK(fabs(m.storage - 100.0) < 0.5 && fabs(m.loss - 20.0) < 0.5);
    CHECK(bushing_modulus_step(&tracker, &state, NAN, 1.0f, &m) == BUSHING_STATUS_REFUSED);
    uint32_t refused = 9, repairs = 9;
    CHECK(bushing_modulus_counts(&state, &refused, &repairs) == BUSHING_STATUS_OK);
    CHECK(refused == 1 && repairs == 0);
    /* Before any sample the modulus is not valid. */
    CHECK(bushing_modulus_reset(&tracker, &state) == BUSHING_STATUS_OK);
    CHECK(bushing_modulus_trial(&tracker, &state, 0.0f, 0.0f, &m) == BUSHING_STATUS_OK);
    CHECK(m.valid == 0 && m.storage == 0.0f);

    spec.bandwidth_hz = 4.0;
    CHECK(bushing_modulus_init(&tracker, &spec, &e) == BUSHING_STATUS_OUT_OF_RANGE);
    CHECK(strcmp(e.param, "bandwidth") == 0);
    spec.bandwidth_hz = 1.0;
    spec.min_snr = 0.0;
    CHECK(bushing_modulus_init(&tracker, &spec, &e) == BUSHING_STATUS_NOT_POSITIVE);
    CHECK(strcmp(e.param, "min_snr") == 0);
    CHECK(bushing_modulus_init(&tracker, NULL, NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_modulus_reset(&blank, &state) == BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_modulus_step(&tracker, &blank_state, 0.0f, 0.0f, &m) ==
          BUSHING_STATUS_NOT_INITIALISED);
    CHECK(bushing_modulus_step(&tracker, &state, 0.0f, 0.0f, NULL) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_modulus_trial(NULL, &state, 0.0f, 0.0f, &m) == BUSHING_STATUS_NULL_POINTER);
    CHECK(bushing_modulus_counts(&state, NULL, &repairs) == BUSHING_STATUS_NULL_POINTER);
}

int main(void)
{
    printf("sizes: bushing_f32_t %zu B, bushing_f32_state_t %zu B, bushing_q16_t %zu B, "
           "bushing_q16_state_t %zu B, bushing_spec_t %zu B, bushing_tracker_t %zu B, "
           "bushing_tracker_state_t %zu B, bushing_modulus_t %zu B, bushing_modulus_state_t %zu B\n",
           sizeof(bushing_f32_t), sizeof(bushing_f32_state_t), sizeof(bushing_q16_t),
           sizeof(bushing_q16_state_t), sizeof(bushing_spec_t), sizeof(bushing_tracker_t),
           sizeof(bushing_tracker_state_t), sizeof(bushing_modulus_t),
           sizeof(bushing_modulus_state_t));
    every_refusal();
    every_name();
    misuse();
    rig_run();
    each_effect();
    modal_tracker();
    modulus_tracker();
    printf("%d checks, %d failed\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
