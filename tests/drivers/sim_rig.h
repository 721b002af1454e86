/* A simulated rotor with faults, its index pulse and an estimator, on the
 * rotor's simulated clock (driven by the test), shared by the driver tests
 * that run minutes of revolutions in a fraction of a second. */
#ifndef SPINDLE_TEST_SIM_RIG_H
#define SPINDLE_TEST_SIM_RIG_H

#include "check.h"
#include "sim_rotor.h"
#include "sync.h"
#include "sync_estimator.h"

/* Faults from spec (sim_faults_parse), applied before the pulse source
 * exists, as the daemon does; *now is the rotor's clock, set to its start. */
static inline void pulse_rig_open(const char *spec, double rpm, struct sim_rotor **rotor, struct sync_source **src,
				  struct sync_estimator **est, int64_t *now)
{
	struct sim_faults f;
	CHECK_EQ(sim_faults_parse(spec, &f), 0);
	*rotor = sim_rotor_create(rpm);
	CHECK(*rotor);
	*now = sim_rotor_start(*rotor);
	sim_rotor_set_now(*rotor, *now);
	CHECK_EQ(sim_rotor_apply_faults(*rotor, &f), 0);
	*src = sync_sim_create_faults(*rotor, &f);
	CHECK(*src);
	struct sync_estimator_config cfg;
	sync_estimator_config_default(&cfg, rpm);
	*est = sync_estimator_create(&cfg);
	CHECK(*est);
}

static inline void pulse_rig_close(struct sim_rotor *rotor, struct sync_source *src, struct sync_estimator *est)
{
	sync_estimator_destroy(est);
	sync_destroy(src);
	sim_rotor_destroy(rotor);
}

#endif
