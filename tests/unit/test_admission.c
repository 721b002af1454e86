/* daemon/admission: the slot kept for an admin, the per-user and
 * in-handshake limits, and that admins are counted against max-clients
 * only. */
#include "admission.h"
#include "check.h"
#include "config.h"

static enum admission_verdict ask(const struct config *cfg, bool admin, uint32_t clients, uint32_t incomplete,
				  uint32_t same_user)
{
	struct admission_load load = { .clients = clients, .incomplete = incomplete, .same_user = same_user };
	return admission_check(cfg, admin, &load);
}

int main(void)
{
	struct config cfg = { .max_clients = 8,
			      .admin_reserved_clients = 1,
			      .max_clients_per_user = 3,
			      .max_incomplete_clients = 2 };
	CHECK_EQ(ask(&cfg, false, 0, 0, 0), ADMISSION_OK);
	CHECK_EQ(ask(&cfg, false, 6, 0, 0), ADMISSION_OK);
	CHECK_EQ(ask(&cfg, false, 7, 0, 0), ADMISSION_FULL); /* the last slot is an admin's */
	CHECK_EQ(ask(&cfg, true, 7, 0, 0), ADMISSION_OK);
	CHECK_EQ(ask(&cfg, true, 8, 0, 0), ADMISSION_FULL);
	CHECK_EQ(ask(&cfg, false, 3, 0, 3), ADMISSION_USER);
	CHECK_EQ(ask(&cfg, true, 3, 5, 5), ADMISSION_OK); /* admins are not limited per user or handshake */
	CHECK_EQ(ask(&cfg, false, 3, 2, 0), ADMISSION_INCOMPLETE);
	CHECK_EQ(ask(&cfg, false, 2, 1, 2), ADMISSION_OK);
	/* With a single slot there is nothing to keep. */
	cfg.max_clients = 1;
	CHECK_EQ(ask(&cfg, false, 0, 0, 0), ADMISSION_OK);
	CHECK_EQ(ask(&cfg, true, 1, 0, 0), ADMISSION_FULL);
	/* More kept, or none. */
	cfg.max_clients = 8;
	cfg.admin_reserved_clients = 3;
	CHECK_EQ(ask(&cfg, false, 4, 0, 0), ADMISSION_OK);
	CHECK_EQ(ask(&cfg, false, 5, 0, 0), ADMISSION_FULL);
	CHECK_EQ(ask(&cfg, true, 7, 0, 0), ADMISSION_OK);
	cfg.admin_reserved_clients = 0;
	CHECK_EQ(ask(&cfg, false, 7, 0, 0), ADMISSION_OK);
	for (int v = ADMISSION_OK; v <= ADMISSION_INCOMPLETE; v++)
		CHECK(admission_reason((enum admission_verdict)v)[0]);
	return check_done();
}
