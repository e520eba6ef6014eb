// The planet's ground under the eye, in float32: cloudcore/atmosphere/geometry.py's distance_to_ground.

// how far a ray at `up` (its cosine to the up) goes to the planet's ground from `altitude` over it, where it meets
// it (else 3e38): h (2 R + h) over the ray's two roots' sum, the form that subtracts no two large numbers, as
// float32 would lose the distance in r mu - sqrt(...)
float distance_to_ground(float altitude, float radius, float up)
{
    float r = radius + altitude;
    float across = r * r * up * up - altitude * (2.0 * radius + altitude);
    return up < 0.0 && across >= 0.0 ? altitude * (2.0 * radius + altitude) / (-r * up + sqrt(across)) : 3.0e38;
}
