/* The daemon process's own resources, apart from what it serves: the
 * signals that stop it, its fd limit, the fds it has open. */
#ifndef SPINDLE_PROCESS_H
#define SPINDLE_PROCESS_H

#include <stdint.h>
#include <systemd/sd-event.h>

/* Blocks the shutdown signals and SIGHUP and handles them on event's loop:
 * the first end the loop (sd_event_exit, so the shutdown path runs),
 * SIGHUP is logged and ignored; SIGPIPE is ignored. 0 or negative errno. */
int process_setup_signals(sd_event *event);

/* Raises the soft fd limit to the hard one, logging what it did. */
void process_raise_fd_limit(void);

/* The fds open now (for the limits event: asked for, never polled). */
uint32_t process_open_fds(void);

#endif
