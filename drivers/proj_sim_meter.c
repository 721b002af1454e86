/* The simulated projector's meter (see proj_sim_meter.h).
 *
 * It runs behind the device model over stretches of time in which the
 * device's state is constant, split further at the rotor's band crossings
 * (known in closed form from the rotor's motion). Lit stretches with a
 * timing are sampled at every slice time the device uses, all N of each
 * revolution: at 396 slices and 730 rpm that is 4,800 rotor angle
 * evaluations a second, a few hundred microseconds of CPU. */
#include "proj_sim_meter.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

#include "sim_rotor.h"

#define ERR_BIN 0.001 /* slices */
#define ERR_BINS 4000 /* up to 4 slices; then one overflow bin */

struct proj_meter {
	struct sim_rotor *rotor;
	uint32_t n;
	double lo, hi; /* the band, rpm */
	int64_t clock; /* measured up to here */
	bool lit;      /* over the last stretch measured */
	int64_t dark_since;
	bool stalled;        /* the rotor, at clock */
	int64_t band_change; /* when stalled next flips */
	int64_t stall_index; /* the last true index before the latest stall */
	bool open;           /* lit in the current stall and not dark since */
	double err_sum;
	uint64_t hist[ERR_BINS + 1];
	struct proj_simdev_stats st;
};

struct proj_meter *proj_meter_create(struct sim_rotor *rotor, uint32_t images_per_rev, double nominal_rpm, int64_t t)
{
	if (images_per_rev == 0 || !(nominal_rpm > 0.0)) {
		errno = EINVAL;
		return NULL;
	}
	struct proj_meter *m = calloc(1, sizeof(*m));
	if (!m)
		return NULL;
	m->rotor = rotor;
	m->n = images_per_rev;
	m->lo = nominal_rpm * (1.0 - PROJ_METER_BAND);
	m->hi = nominal_rpm * (1.0 + PROJ_METER_BAND);
	m->clock = m->dark_since = t; /* dark at power-up */
	m->band_change = sim_rotor_band_cross(rotor, t, m->lo, m->hi, false);
	m->st.angle_err_p50 = m->st.angle_err_p99 = m->st.angle_err_max = -1.0;
	return m;
}

void proj_meter_destroy(struct proj_meter *m)
{
	free(m);
}

static void record_delay(struct proj_meter *m, int64_t delay)
{
	m->st.last_dark_delay_ns = delay;
	if (delay > m->st.max_dark_delay_ns)
		m->st.max_dark_delay_ns = delay;
}

static void went_dark(struct proj_meter *m, int64_t t)
{
	m->dark_since = t;
	if (m->open)
		record_delay(m, t - m->stall_index);
	m->open = false;
}

/* The rotor crosses the band edge at the meter's clock. */
static void band_flip(struct proj_meter *m)
{
	int64_t t = m->clock;
	m->stalled = !m->stalled;
	if (m->stalled) {
		m->st.stalls++;
		m->stall_index = sim_rotor_index_time(m->rotor, sim_rotor_revolution(m->rotor, t));
		m->open = m->lit;
		if (!m->lit)
			record_delay(m, m->dark_since > m->stall_index ? m->dark_since - m->stall_index : 0);
	} else if (m->open) {
		record_delay(m, t - m->stall_index); /* lit all through: a failure */
		m->st.lit_through++;
		m->open = false;
	}
	int64_t next = sim_rotor_band_cross(m->rotor, t, m->lo, m->hi, m->stalled);
	m->band_change = next > t ? next : t + 1;
}

static void add_error(struct proj_meter *m, double e)
{
	double a = fabs(e);
	size_t bin = (size_t)fmin(a / ERR_BIN, ERR_BINS);
	m->hist[bin]++;
	m->err_sum += e;
	m->st.slices++;
	if (a > m->st.angle_err_max)
		m->st.angle_err_max = a;
}

/* Every slice time the device uses in [from, to): slice s (counted from
 * the timing's index) at index + period * s / N shows image s mod N. */
static void sample(struct proj_meter *m, int64_t from, int64_t to, const struct projwire_timing *tm)
{
	double n = m->n, step = (double)tm->period_ns / n;
	for (int64_t s = (int64_t)ceil((double)(from - tm->index_ns) / step);; s++) {
		int64_t t = tm->index_ns + llround((double)s * step);
		if (t < from)
			continue; /* rounding at the start */
		if (t >= to)
			break;
		int64_t k = s % (int64_t)m->n;
		double e = sim_rotor_angle(m->rotor, t) / (2.0 * M_PI) * n - (double)(k < 0 ? k + m->n : k);
		e -= n * round(e / n);
		add_error(m, e <= -n / 2 ? e + n : e);
	}
}

static void stretch(struct proj_meter *m, int64_t to, bool lit, const struct projwire_timing *timing)
{
	int64_t from = m->clock;
	if (!lit) {
		if (m->lit)
			went_dark(m, from);
		m->lit = false;
		return;
	}
	m->lit = true;
	if (m->stalled) {
		m->st.lit_stopped_ns += to - from;
		m->open = true; /* lit in a stall: dark delay counts from its index */
	}
	if (!timing) {
		m->st.lit_untimed_ns += to - from;
		return;
	}
	sample(m, from, to, timing);
}

void proj_meter_run(struct proj_meter *m, int64_t to, bool lit, const struct projwire_timing *timing)
{
	while (m->clock < to) {
		int64_t step = to < m->band_change ? to : m->band_change;
		stretch(m, step, lit, timing);
		m->clock = step;
		if (step == m->band_change)
			band_flip(m);
	}
	if (m->lit && !lit) /* went dark at 'to' itself */
		stretch(m, to, lit, timing);
}

static double percentile(const struct proj_meter *m, double q)
{
	uint64_t need = (uint64_t)ceil(q * (double)m->st.slices), cum = 0;
	for (size_t i = 0; i <= ERR_BINS; i++) {
		cum += m->hist[i];
		if (cum >= need && cum > 0)
			return i == ERR_BINS ? m->st.angle_err_max
					     : fmin((double)(i + 1) * ERR_BIN, m->st.angle_err_max);
	}
	return m->st.angle_err_max;
}

void proj_meter_get(const struct proj_meter *m, struct proj_simdev_stats *out)
{
	uint64_t dog = out->watchdog_blanks;
	*out = m->st;
	out->watchdog_blanks = dog;
	if (!m->st.slices)
		return;
	out->angle_err_p50 = percentile(m, 0.50);
	out->angle_err_p99 = percentile(m, 0.99);
	out->angle_err_mean = m->err_sum / (double)m->st.slices;
}
