/* lru.h: an intrusive list in least-recently-used order, the one list
 * every cache in glint keeps (precomputations, decoded paintings, material
 * documents, loaded scenes, GL meshes).
 *
 * Embed an lru_node in the cached object and recover the object with
 * lru_entry().  The head is the most recently used node, the tail the
 * least.  A list does not own its nodes: removing a node never frees it.
 * Not thread-safe by itself: the cache that owns a list holds its lock
 * around every call.  None of these functions can fail. */
#ifndef GLINT_LRU_H
#define GLINT_LRU_H

#include <stddef.h>

typedef struct lru_node {
    struct lru_node *prev, *next; /* prev: more recently used */
} lru_node;

typedef struct lru_list {
    lru_node *head, *tail;
    size_t n;
} lru_list;

/* The object that embeds `node` as its member `member`. */
#define lru_entry(node, type, member) ((type *)(void *)((char *)(node) - offsetof(type, member)))

/* Insert a node that is in no list at the head (most recently used). */
static inline void lru_push(lru_list *l, lru_node *x)
{
    x->prev = NULL;
    x->next = l->head;
    if (l->head)
        l->head->prev = x;
    l->head = x;
    if (!l->tail)
        l->tail = x;
    l->n++;
}

/* Take a node out of the list (it must be in this list). */
static inline void lru_remove(lru_list *l, lru_node *x)
{
    if (x->prev)
        x->prev->next = x->next;
    else
        l->head = x->next;
    if (x->next)
        x->next->prev = x->prev;
    else
        l->tail = x->prev;
    x->prev = x->next = NULL;
    l->n--;
}

/* Mark a node of the list as just used (move it to the head). */
static inline void lru_touch(lru_list *l, lru_node *x)
{
    if (l->head == x)
        return;
    lru_remove(l, x);
    lru_push(l, x);
}

/* The least recently used node (NULL when empty); walk towards the head
 * with node->prev. */
static inline lru_node *lru_oldest(const lru_list *l)
{
    return l->tail;
}

#endif
