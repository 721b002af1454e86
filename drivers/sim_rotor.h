/* The simulated rotor: a spinning screen with a true angle over time, shared
 * by the simulated sync source and the simulated projector. */
#ifndef SPINDLE_SIM_ROTOR_H
#define SPINDLE_SIM_ROTOR_H

#include <stdint.h>

struct sim_rotor;

/* A rotor turning at rpm from now (CLOCK_MONOTONIC), angle 0 at creation.
 * NULL + errno on failure. */
struct sim_rotor *sim_rotor_create(double rpm);
/* Accepts NULL. */
void sim_rotor_destroy(struct sim_rotor *r);

/* True period (ns) and the time of the first revolution start (angle 0)
 * at or after t. */
int64_t sim_rotor_period_ns(const struct sim_rotor *r);
int64_t sim_rotor_next_index(const struct sim_rotor *r, int64_t t);
/* True angle in radians [0, 2*pi) at time t. */
double sim_rotor_angle(const struct sim_rotor *r, int64_t t);

/* Number of the revolution in progress at t: 0 from creation, counting up at
 * each revolution start (negative before creation). */
int64_t sim_rotor_revolution(const struct sim_rotor *r, int64_t t);
/* True start time of revolution n. */
int64_t sim_rotor_index_time(const struct sim_rotor *r, int64_t n);

#endif
