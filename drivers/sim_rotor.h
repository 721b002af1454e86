/* The simulated rotor: a spinning screen with a true angle over time, shared
 * by the simulated sync source and the simulated projector.
 *
 * Fault model. The rotor is heavy: its true motion is smooth, a chain of
 * segments each of constant angular acceleration (a speed ramp, a stop, a
 * spin-up, a slow drift) or constant speed. Everything that makes the index
 * pulse train irregular on a healthy rotor (edge jitter, missed pulses,
 * glitch edges) is in the sensing, not the motion: sync_sim adds it to what
 * it reports and the true revolution starts never see it. So the simulated
 * projector, which measures slice angles against the true motion, shows how
 * well the estimator sees through the sensor noise. */
#ifndef SPINDLE_SIM_ROTOR_H
#define SPINDLE_SIM_ROTOR_H

#include <stdbool.h>
#include <stdint.h>

#define SIM_ROTOR_NEVER INT64_MAX /* no such index time: the rotor stays stopped */

struct sim_rotor;

/* A rotor turning at rpm from now (CLOCK_MONOTONIC), angle 0 at creation.
 * NULL + errno on failure. */
struct sim_rotor *sim_rotor_create(double rpm);
/* Accepts NULL. */
void sim_rotor_destroy(struct sim_rotor *r);

/* The rotor's clock: CLOCK_MONOTONIC, or after sim_rotor_set_now() a
 * simulated clock that only moves when told to, so a test can run
 * simulated revolutions faster than real time. Everything built on the
 * rotor (sync_sim, the simulated projector) reads time here. */
int64_t sim_rotor_now(const struct sim_rotor *r);
/* Switches r to the simulated clock, reading t from now on (t must not go
 * backwards). For tests; the daemon never calls it. */
void sim_rotor_set_now(struct sim_rotor *r, int64_t t);
/* When r was created (revolution 0 starts there). */
int64_t sim_rotor_start(const struct sim_rotor *r);

/* From time t on, the speed changes linearly to rpm over dur_ns (0: at
 * once), then holds (drifting by drift_ppm_s of the nominal speed per
 * second, see below). rpm 0 is a stall (dur_ns 0: stopped dead at t). The
 * motion after t is replaced; before t it is kept, so calls are made in
 * time order. 0, or -EINVAL for a bad rpm or duration, -ENOMEM. */
int sim_rotor_set_speed(struct sim_rotor *r, int64_t t, double rpm, int64_t dur_ns);
/* A continuous slow speed change of ppm of the nominal speed per second,
 * applied to every constant-speed stretch scheduled from now on (not to
 * ramps nor to a stopped rotor); the speed never drifts below 0. */
void sim_rotor_set_drift(struct sim_rotor *r, double ppm_per_s);

/* The nominal period (ns) at the creation speed. */
int64_t sim_rotor_period_ns(const struct sim_rotor *r);
/* True speed (rpm) at time t; 0 while stopped. */
double sim_rotor_rpm_at(const struct sim_rotor *r, int64_t t);
/* The first time >= t at which the speed is outside [lo, hi] rpm (inside,
 * with inside true); SIM_ROTOR_NEVER if it never is. */
int64_t sim_rotor_band_cross(const struct sim_rotor *r, int64_t t, double lo, double hi, bool inside);

/* The time of the first revolution start (angle 0) at or after t;
 * SIM_ROTOR_NEVER when the rotor stops for good before the next one. */
int64_t sim_rotor_next_index(const struct sim_rotor *r, int64_t t);
/* Half-turn starts: the revolution starts (angle 0) and the times the rotor
 * is half a turn past them (angle pi), where a mirrored display starts
 * image N/2, the first image of its volume mirrored. Half-turn h is at
 * position h / 2 revolutions since creation: even h is revolution h / 2's
 * start, to the nanosecond of sim_rotor_index_time(). Its time, as
 * index_time() (SIM_ROTOR_NEVER when the rotor never gets there). */
int64_t sim_rotor_half_turn_time(const struct sim_rotor *r, int64_t h);
/* The first half-turn start at or after t (SIM_ROTOR_NEVER as
 * next_index()); *second, when given, is true for angle pi (the middle of
 * a revolution), false for a revolution start. */
int64_t sim_rotor_next_half_turn(const struct sim_rotor *r, int64_t t, bool *second);
/* True angle in radians [0, 2*pi) at time t. */
double sim_rotor_angle(const struct sim_rotor *r, int64_t t);

/* Number of the revolution in progress at t: 0 from creation, counting up at
 * each revolution start (negative before creation). */
int64_t sim_rotor_revolution(const struct sim_rotor *r, int64_t t);
/* True start time of revolution n: the first whole nanosecond at which the
 * rotor has turned n revolutions since creation; SIM_ROTOR_NEVER when it
 * never gets there. revolution() and index_time() agree exactly. */
int64_t sim_rotor_index_time(const struct sim_rotor *r, int64_t n);

/* A fault description, from text (sim_faults_parse) or filled by hand.
 * Event times are seconds after the rotor's creation. */
#define SIM_FAULTS_MAX_EVENTS 8

enum sim_fault_kind { SIM_FAULT_SPEED, SIM_FAULT_STALL, SIM_FAULT_UNPLUG };

struct sim_fault_event {
	enum sim_fault_kind kind;
	double at;      /* s after creation */
	double rpm;     /* SPEED: target speed */
	double dur;     /* SPEED: ramp time; STALL: deceleration time (0: dead stop) */
	double restart; /* STALL: s after at until spin-up starts; UNPLUG: until
			 * re-plugged; < 0 never */
	double spinup;  /* STALL: spin-up time back to nominal */
};

struct sim_faults {
	double jitter;      /* RMS deviation of measured periods, fraction of the period */
	double missed;      /* probability that a revolution's pulse is lost */
	double extra;       /* probability of one glitch edge within a revolution */
	double drift_ppm_s; /* slow speed change, ppm of nominal per second */
	uint64_t seed;      /* of the pulse-fault random numbers */
	uint32_t nevents;
	struct sim_fault_event events[SIM_FAULTS_MAX_EVENTS];
};

/* Parses a spec: comma-separated key=value items, each key at most once
 * except speed, stall and unplug (up to SIM_FAULTS_MAX_EVENTS in all), "" or
 * "none" for no faults:
 *   jitter=F            F in [0, 0.1]: measured period RMS / period
 *   missed=P, extra=P   P in [0, 1]: probability per revolution
 *   drift=Xppm/s        X in [-10000, 10000]
 *   seed=N              unsigned decimal
 *   speed=T:RPM@D       at T s, ramp to RPM (1..100000) over D s
 *   stall=T[/D][+R[/S]] at T s decelerate to 0 over D s (default 0: dead
 *                       stop); R s after T spin up to nominal over S s
 *                       (default 1); without +R it never restarts
 *   unplug=T[+R]        at T s the simulated projector is unplugged (its
 *                       buffers lost), and plugged in again R s later
 *                       (proj_sim.c); without +R it stays away
 * Numbers are plain decimals (strtod, no inf/nan), times >= 0. Fills out
 * (zeroed first) and returns 0, or -EINVAL for anything else. */
int sim_faults_parse(const char *spec, struct sim_faults *out);

/* Schedules the motion faults (drift, speed, stall) of f on r, events in
 * time order. 0 or negative errno. Pulse faults are for sync_sim, unplug
 * events for proj_sim. */
int sim_rotor_apply_faults(struct sim_rotor *r, const struct sim_faults *f);

#endif
