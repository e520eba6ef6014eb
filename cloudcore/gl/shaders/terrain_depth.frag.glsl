#version 420 core
// The terrain's depth alone (the light shafts' march reads it: cloudcore/gl/light_shafts.py): no colour.

void main()
{
}
