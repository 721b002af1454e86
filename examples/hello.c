/* hello: the smallest complete Spindle client (README.md, "Writing a
 * client"). Shows an orange triangle standing on the display's axis,
 * waits until it is on the display, prints the volume it is shown in,
 * keeps it there for the seconds given (default 0) and exits: the layer
 * goes with the connection.
 *
 *   hello [SECONDS]        (socket: $SPINDLE_SOCKET, else the default) */
#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <spindle/spindle.h>

int main(int argc, char **argv)
{
	if (argc > 2 || (argc == 2 && (argv[1][0] < '0' || argv[1][0] > '9'))) {
		bool help = !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h");
		fprintf(help ? stdout : stderr,
			"usage: hello [SECONDS]   (socket: $SPINDLE_SOCKET, else the default)\n");
		return help ? 0 : 2;
	}
	unsigned hold = argc > 1 ? (unsigned)atoi(argv[1]) : 0;
	struct spindle *sp = spindle_connect(NULL);
	if (!sp) {
		fprintf(stderr, "hello: cannot connect to spindled: %s\n", strerror(errno));
		return 1;
	}
	/* Volume space: y up along the rotation axis, display radius 1. */
	const float tri[] = { 0, 0.5f, 0, -0.5f, -0.5f, 0, 0.5f, -0.5f, 0 };
	struct spindle_buffer *buf = spindle_buffer_create(sp, tri, sizeof(tri));
	struct spindle_list *list = spindle_list_create(sp);
	struct spindle_layer *layer = spindle_layer_create(sp);
	struct spindle_frame frame;
	int r = !buf || !list || !layer ? -errno : 0;
	if (r == 0)
		r = spindle_list_set_color(list, 255, 128, 0, 255);
	if (r == 0)
		r = spindle_list_triangles(list, buf, 0, 3, 0);
	if (r == 0)
		r = spindle_layer_set_list(layer, list);
	if (r == 0)
		r = spindle_commit_and_wait(sp, &frame);
	if (r < 0) {
		fprintf(stderr, "hello: %s\n", spindle_get_error(sp) ? spindle_get_error(sp) : strerror(-r));
		spindle_disconnect(sp);
		return 1;
	}
	printf("hello: shown in volume %llu (libspindle %s, protocol %u)\n", (unsigned long long)frame.volume_seq,
	       spindle_library_version(), spindle_get_version(sp));
	sleep(hold);
	spindle_disconnect(sp);
	return 0;
}
