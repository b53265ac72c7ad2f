-- Returns something that is not a model.
return 42
