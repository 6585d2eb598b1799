/* nav_loop.c: the estimator inside a 1 Hz navigation loop, as a C firmware runs it.
 *
 * Each second: read the RINS's sample, step the estimator, pass the corrected attitude on; every
 * 60 s save a checkpoint to (here: simulated) flash; at boot, restore the last checkpoint if there
 * is a good one. docs/c-api.md walks through it.
 *
 * To run on its own, the "RINS" here is simulated: a ship swaying 3 deg in roll and 1 deg in pitch
 * at 30 deg latitude, a one-way rotation of 480 s, and the attitude oscillation of eq (2) for
 * known installation errors. Halfway through, the power is cut: the program boots again from the
 * last checkpoint. It exits 0 when every estimated error is within 1 arcsec of the truth at the
 * end, 1 otherwise. `bash scripts/c-nav-loop.sh` builds it for a Cortex-M4F and runs it in QEMU. */

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "rins_estimator.h"

/* ---- The firmware's side: what a real navigation computer provides. ---- */

/* The RINS's output for second `t_s` (here simulated; see the end of the file). */
static void read_rins_sample(double t_s, RinsSample *sample);

/* A flash sector for one checkpoint image (here a RAM array; `valid` stands for the firmware's
 * own record that a write completed, e.g. a sequence number written last). */
static uint8_t flash_image[RINS_CHECKPOINT_LEN];
static int flash_valid = 0;

static void flash_write(const uint8_t *image, size_t len) {
    memcpy(flash_image, image, len);
    flash_valid = 1;
}

/* The estimator's memory, one block per estimator, aligned as the header asks. */
static _Alignas(RINS_ESTIMATOR_ALIGN) unsigned char estimator_memory[RINS_ESTIMATOR_SIZE];
/* The checkpoint is written here first, then to flash (RINS_CHECKPOINT_LEN bytes). */
static uint8_t checkpoint_buffer[RINS_CHECKPOINT_LEN];

/* Boot: a fresh estimator, then the saved state if there is a good one. */
static RinsEstimator *boot(void) {
    RinsConfig config;
    RinsEstimator *estimator = NULL;
    RinsError e;
    rins_config_default(&config);
    config.rotation_period_s = 480.0; /* known from the RINS's maker: no need to detect it */
    /* (rins_config_check(&config, message, size) would say which setting is out of bounds.) */
    e = rins_estimator_init(estimator_memory, sizeof estimator_memory, &config, &estimator);
    if (e != RINS_ERROR_OK) {
        fprintf(stderr, "init: %s\n", rins_error_name(e));
        return NULL;
    }
    if (flash_valid) {
        /* A damaged or foreign image is refused and changes nothing: run on fresh. */
        e = rins_estimator_restore(estimator, flash_image, sizeof flash_image);
        fprintf(stderr, "boot: checkpoint %s\n", e == RINS_ERROR_OK ? "restored" : rins_error_name(e));
    }
    return estimator;
}

/* One second of the navigation loop. Returns 0, or -1 on a library error. */
static int navigation_step(RinsEstimator *estimator, double t_s) {
    RinsSample sample;
    RinsOutput out;
    RinsError e;
    read_rins_sample(t_s, &sample);
    e = rins_estimator_step(estimator, &sample, &out);
    if (e == RINS_ERROR_OK) {
        /* Pass on out.heading/roll/pitch_corrected_rad; out.status says how far the estimate is
         * (RINS_STATUS_CONVERGED: every 1-sigma below 1 arcsec). */
    } else if (e == RINS_ERROR_SAMPLE_REJECTED) {
        /* A bad sample: the estimator is unchanged. Pass the raw attitude on; out.status says why. */
    } else {
        fprintf(stderr, "step: %s\n", rins_error_name(e));
        return -1;
    }
    if ((long)t_s % 60 == 59) {
        size_t written;
        if (rins_estimator_checkpoint(estimator, checkpoint_buffer, sizeof checkpoint_buffer, &written) == RINS_ERROR_OK) {
            flash_write(checkpoint_buffer, written);
        }
    }
    return 0;
}

static const double TRUE_X_ARCSEC[4] = {200.0, -150.0, 300.0, -250.0};

/* ---- Attitude at the navigation rate: 100 Hz between the 1 Hz steps. ---- */

/* The Cortex-M SysTick, counting down at the core clock: QEMU mps2-an386 run with
 * `-icount shift=0` runs one instruction a nanosecond and ticks at 25 MHz, 40 instructions a
 * tick (scripts/c-nav-loop.sh runs it so). On a board it counts the core's cycles. */
#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)
#define INSTRUCTIONS_PER_TICK 40u

static uint32_t compensate_calls = 0, compensate_max_ticks = 0, compensate_off = 0;

/* The 99 attitude samples of the 10 ms between the steps at `t_s` and `t_s + 1`, each compensated
 * with the estimate of the last step (the estimator is not stepped): the corrected roll and pitch
 * are the ship's own sway, eq (2)'s oscillation of hundreds of arcsec removed. */
static void navigation_rate_attitude(const RinsEstimator *estimator, double t_s) {
    int i;
    for (i = 1; i < 100; i++) {
        RinsSample sample;
        RinsAttitude attitude;
        uint32_t before, ticks;
        RinsError e;
        double t = t_s + 0.01 * i, roll_sway_rad, pitch_sway_rad;
        read_rins_sample(t, &sample);
        before = SYST_CVR;
        e = rins_estimator_compensate(estimator, &sample, &attitude);
        ticks = (before - SYST_CVR) & 0xFFFFFFu;
        if (e != RINS_ERROR_OK) {
            continue; /* no estimate yet: pass the RINS's own attitude on */
        }
        compensate_calls++;
        if (ticks > compensate_max_ticks) {
            compensate_max_ticks = ticks;
        }
        roll_sway_rad = 3.0 * sin(2.0 * 3.14159265358979323846 * t / 8.0) * RINS_RAD_PER_DEG;
        pitch_sway_rad = 1.0 * sin(2.0 * 3.14159265358979323846 * t / 11.0) * RINS_RAD_PER_DEG;
        if (fabs(attitude.roll_rad - roll_sway_rad) * RINS_ARCSEC_PER_RAD > 1.0 ||
            fabs(attitude.pitch_rad - pitch_sway_rad) * RINS_ARCSEC_PER_RAD > 1.0) {
            compensate_off++;
        }
    }
}

int main(void) {
    RinsEstimator *estimator;
    RinsEstimate estimate;
    int ok = 1;
    long t;
    fprintf(stderr, "estimator: %lu of the RINS_ESTIMATOR_SIZE = %lu bytes; checkpoint image: %lu bytes\n",
            (unsigned long)rins_estimator_size(), (unsigned long)RINS_ESTIMATOR_SIZE, (unsigned long)RINS_CHECKPOINT_LEN);
    estimator = boot();
    if (!estimator) {
        return 1;
    }
    SYST_RVR = 0xFFFFFFu;
    SYST_CVR = 0u;
    SYST_CSR = 5u; /* enabled, core clock, no interrupt */
    for (t = 0; t < 4000; t++) {
        if (t == 2030) {
            /* Power cut 30 s after the last checkpoint: the firmware boots again. */
            memset(estimator_memory, 0, sizeof estimator_memory);
            estimator = boot();
            if (!estimator) {
                return 1;
            }
            /* The samples of the last 30 s before the cut were lost with the RAM. */
        }
        if (navigation_step(estimator, (double)t) != 0) {
            return 1;
        }
        if (t >= 3900) {
            navigation_rate_attitude(estimator, (double)t);
        }
    }
    /* Eq (2) at the navigation rate: within 1 arcsec of the sway once the estimate is. */
    printf("compensate: %lu samples at 100 Hz, at most %lu instructions each (%lu SysTick ticks), %lu beyond 1 arcsec\n",
           (unsigned long)compensate_calls, (unsigned long)(compensate_max_ticks * INSTRUCTIONS_PER_TICK),
           (unsigned long)compensate_max_ticks, (unsigned long)compensate_off);
    ok = compensate_calls == 100u * 99u && compensate_off == 0;
    if (rins_estimator_estimate(estimator, &estimate) != RINS_ERROR_OK) {
        fprintf(stderr, "no estimate after 4000 s\n");
        return 1;
    }
    for (t = 0; t < 4; t++) {
        double x_arcsec = estimate.x_rad[t] * RINS_ARCSEC_PER_RAD;
        double sigma_arcsec = estimate.sigma_rad[t] * RINS_ARCSEC_PER_RAD;
        double off_arcsec = x_arcsec - TRUE_X_ARCSEC[t];
        printf("x%ld = %9.3f arcsec (1-sigma %.3f), off by %6.3f\n", t + 1, x_arcsec, sigma_arcsec, off_arcsec);
        ok = ok && fabs(off_arcsec) < 1.0;
    }
    return ok ? 0 : 1;
}

/* ---- The simulated RINS. ---- */

static void read_rins_sample(double t_s, RinsSample *s) {
    const double pi = 3.14159265358979323846, earth_rate_rad_per_s = 7.292115e-5;
    const double latitude_rad = 30.0 * RINS_RAD_PER_DEG;
    double x[4], rho, p, sl, cl, d_heading, d_roll, d_pitch;
    int i;
    for (i = 0; i < 4; i++) {
        x[i] = TRUE_X_ARCSEC[i] / RINS_ARCSEC_PER_RAD;
    }
    rho = 2.0 * pi * t_s / 480.0;       /* rotation angle */
    p = earth_rate_rad_per_s * t_s;      /* platform angle */
    sl = sin(latitude_rad);
    cl = cos(latitude_rad);
    /* Eq (2): the attitude errors the installation errors cause. */
    d_heading = -x[0] * cl * cos(rho - p) - x[1] * cl * sin(rho - p) - x[2] * sl * sin(rho) + x[3] * sl * cos(rho);
    d_roll = -x[0] * sl * cos(rho - p) - x[1] * sl * sin(rho - p) + x[2] * cl * sin(rho) - x[3] * cl * cos(rho);
    d_pitch = x[0] * sin(rho - p) - x[1] * cos(rho - p);
    s->time_s = t_s;
    s->rotation_deg = rho / RINS_RAD_PER_DEG;
    s->platform_deg = p / RINS_RAD_PER_DEG;
    s->latitude_deg = 30.0;
    s->heading_deg = 45.0 + d_heading / RINS_RAD_PER_DEG;
    s->roll_deg = 3.0 * sin(2.0 * pi * t_s / 8.0) + d_roll / RINS_RAD_PER_DEG;
    s->pitch_deg = 1.0 * sin(2.0 * pi * t_s / 11.0) + d_pitch / RINS_RAD_PER_DEG;
}
