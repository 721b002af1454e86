/* Intrusive doubly linked lists. */
#ifndef SPINDLE_LINK_H
#define SPINDLE_LINK_H

#include <stdbool.h>
#include <stddef.h>

struct link {
	struct link *prev, *next;
};

static inline void link_init(struct link *head)
{
	head->prev = head->next = head;
}

static inline bool link_empty(const struct link *head)
{
	return head->next == head;
}

/* Inserts elem before head, i.e. at the tail of the list head. */
static inline void link_append(struct link *head, struct link *elem)
{
	elem->prev = head->prev;
	elem->next = head;
	head->prev->next = elem;
	head->prev = elem;
}

static inline void link_remove(struct link *elem)
{
	elem->prev->next = elem->next;
	elem->next->prev = elem->prev;
	elem->prev = elem->next = elem;
}

/* clang-format 14 takes "(ptr) - offsetof" for a cast of a unary minus. */
/* clang-format off */
#define link_entry(ptr, type, member) ((type *)((char *)(ptr) - offsetof(type, member)))
/* clang-format on */

#define link_for_each(pos, head, member)                                                       \
	for (pos = link_entry((head)->next, __typeof__(*pos), member); &pos->member != (head); \
	     pos = link_entry(pos->member.next, __typeof__(*pos), member))

#define link_for_each_safe(pos, tmp, head, member)                        \
	for (pos = link_entry((head)->next, __typeof__(*pos), member),    \
	    tmp = link_entry(pos->member.next, __typeof__(*pos), member); \
	     &pos->member != (head); pos = tmp, tmp = link_entry(pos->member.next, __typeof__(*pos), member))

#endif
