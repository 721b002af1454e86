#include "admission.h"

#include "config.h"

enum admission_verdict admission_check(const struct config *cfg, bool admin, const struct admission_load *load)
{
	uint32_t room = cfg->max_clients;
	if (!admin) /* the admins' slots, while there is room for one client more */
		room = cfg->admin_reserved_clients < room ? room - cfg->admin_reserved_clients : (room ? 1 : 0);
	if (load->clients >= room)
		return ADMISSION_FULL;
	if (admin)
		return ADMISSION_OK;
	if (load->same_user >= cfg->max_clients_per_user)
		return ADMISSION_USER;
	if (load->incomplete >= cfg->max_incomplete_clients)
		return ADMISSION_INCOMPLETE;
	return ADMISSION_OK;
}

const char *admission_reason(enum admission_verdict v)
{
	switch (v) {
	case ADMISSION_OK:
		return "admitted";
	case ADMISSION_FULL:
		return "too many clients";
	case ADMISSION_USER:
		return "too many clients of this user";
	case ADMISSION_INCOMPLETE:
		return "too many clients still in their handshake";
	}
	return "refused";
}
