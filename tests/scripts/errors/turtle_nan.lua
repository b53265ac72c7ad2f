-- NaN angle.
return pge.turtle{ angle = 0/0 }
