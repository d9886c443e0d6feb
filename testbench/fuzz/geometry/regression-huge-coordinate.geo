rbcd-geometry 1
screen 64 48
view 1 0 0 0 0 1 0 0 0 0 -1 -1 0 0 -1 0
part 1 8 12 cube1
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 0 0 1
v 1 0 1
v 0 1 1
v 1 1 1
t 0 2 1
t 1 2 3
t 4 5 6
t 5 7 6
t 0 1 4
t 1 5 4
t 2 6 3
t 3 6 7
t 0 4 2
t 2 4 6
t 1 3 5
t 3 7 5
part 2 8 12 cube2
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 0 0 1
v 1 0 1
v 0 1 1
v 1 1 1
t 0 2 1
t 1 2 3
t 4 5 6
t 5 7 6
t 0 1 4
t 1 5 4
t 2 6 3
t 3 6 7
t 0 4 2
t 2 4 6
t 1 3 5
t 3 7 5
frame 0
m 0 1 0 0 0 0 1 0 0 0 0 1 0
m 1 1 0 0 1e308 0 1 0 0 0 0 1 0
frame 1
m 0 1 0 0 0 0 1 0 0 0 0 1 0
m 1 0 -2 0 3 2 0 0 0 0 0 2 0
