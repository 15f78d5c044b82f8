# Lesson terminal-basics: your notes. The grader never runs this file; it
# looks at the files and folders your commands make in terminal_basics/.
# Type each command in a terminal whose current folder is terminal_basics/
# (check with pwd), then write it under its TODO so you remember it.

# TODO 1: make a folder called a_folder

# TODO 2: make an empty file a_folder/an_empty_file.txt

# TODO 3: with nano, make file_with_stuff.txt holding the word stuff
#         (save and leave nano with Ctrl+X, then Y, then Enter)

# TODO 4: add the line "first line" to appended.txt with echo and >>

# TODO 5: add the line "second line" to appended.txt with echo and >>

# TODO 6 (last!): save what ls prints into result_of_ls.txt with >
