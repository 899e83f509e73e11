#version 430
flat in uint item;
out uint out_item;

void main() {
    out_item = item;
}
